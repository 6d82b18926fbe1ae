//! The page at `/`, served by a real server on port 0 (SQLite) and used in a real browser: Debian's
//! Chromium driven through chromedriver. With `WINDMETA_REQUIRE_BROWSER=1` (CI) a missing browser
//! is a failure; without it the browser test says why it did not run.

use crate::harness::app::{TestApp, database, spawn_app_configured};
use fantoccini::key::Key;
use fantoccini::{Client, ClientBuilder, Locator};
use serde_json::{Value, json};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

const KEY: &str = "browser-test-key";

/// The page, its assets and their headers: the policy, the caching, the digests in the addresses.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_page_is_served_with_its_policy_and_caching() {
    let app = spawn_app_configured(&database("page-served"), |args| args.api_keys = vec![KEY.into()]).await;
    let client = reqwest::Client::new();
    let page = client.get(format!("{}/", app.address)).send().await.unwrap();
    assert_eq!(page.status(), 200, "the page needs no key");
    let header = |r: &reqwest::Response, name: &str| r.headers()[name].to_str().unwrap().to_string();
    assert_eq!(header(&page, "content-type"), "text/html; charset=utf-8");
    assert_eq!(header(&page, "cache-control"), "no-cache");
    let policy = header(&page, "content-security-policy");
    assert!(policy.starts_with("default-src 'self'; script-src 'self'; style-src 'self'"), "{policy}");
    assert!(!policy.contains("unsafe"), "{policy}");
    assert_eq!(header(&page, "x-content-type-options"), "nosniff");
    let etag = header(&page, "etag");
    let html = page.text().await.unwrap();
    // Nothing inline that the policy would block, nothing from elsewhere.
    let handler = html.split_whitespace().any(|word| word.starts_with("on") && word.contains('='));
    assert!(!html.contains("style=") && !html.contains("<script>") && !handler, "inline code in the page");
    assert!(!html.contains("http://") && !html.contains("https://"), "the page names another host");

    let again = client.get(format!("{}/", app.address)).header("If-None-Match", &etag).send().await.unwrap();
    assert_eq!(again.status(), 304);

    // The page names one module and the style sheet; every module names what it imports by its
    // versioned address, so every asset is reached through versioned addresses only.
    let script = "text/javascript; charset=utf-8";
    let mut pending = vec![address_of(&html, "app.js"), address_of(&html, "style.css")];
    let mut seen = Vec::new();
    while let Some(address) = pending.pop() {
        let versioned = client.get(format!("{}{address}", app.address)).send().await.unwrap();
        assert_eq!(versioned.status(), 200, "{address}");
        let content_type = if address.contains(".js?") { script } else { "text/css; charset=utf-8" };
        assert_eq!(header(&versioned, "content-type"), content_type);
        assert_eq!(header(&versioned, "cache-control"), "public, max-age=31536000, immutable");
        assert!(address.ends_with(header(&versioned, "etag").trim_matches('"')), "the address carries the digest");
        let unversioned = address.split('?').next().unwrap().to_string();
        let stale = client.get(format!("{}{unversioned}?v=0000", app.address)).send().await.unwrap();
        assert_eq!(header(&stale, "cache-control"), "no-cache", "an old address is not kept");
        let body = versioned.text().await.unwrap();
        for import in body.lines().filter_map(|line| line.split(" from '").nth(1)) {
            let target = import.trim_end_matches("';");
            assert!(target.contains("?v="), "{address} imports {target} without its version");
            let target = format!("/assets/{}", target.trim_start_matches("./"));
            if !seen.contains(&target) && !pending.contains(&target) {
                pending.push(target);
            }
        }
        seen.push(unversioned);
    }
    let modules = ["charts.js", "client.js", "operations.js", "analyses.js", "metamodels.js", "app.js"];
    for name in modules.iter().chain(&["style.css"]) {
        assert!(seen.contains(&format!("/assets/{name}")), "{name} is not reached from the page: {seen:?}");
    }
    let missing = client.get(format!("{}/assets/other.js", app.address)).send().await.unwrap();
    assert_eq!(missing.status(), 404);
    assert_eq!(header(&missing, "content-type"), "application/problem+json");
    let api = client.get(format!("{}/v1/metamodels", app.address)).send().await.unwrap();
    assert_eq!(api.status(), 401, "the API behind the page still needs the key");
    app.stop().await;
}

/// The versioned address the page gives an asset.
fn address_of(html: &str, asset: &str) -> String {
    let start = html.find(&format!("/assets/{asset}?v=")).unwrap_or_else(|| panic!("{asset} is not linked"));
    html[start..].chars().take_while(|c| *c != '"').collect()
}

/// chromedriver and Chromium, from `WINDMETA_CHROMEDRIVER`/`WINDMETA_CHROMIUM` or Debian's paths.
fn browser() -> Option<(PathBuf, PathBuf)> {
    let path =
        |variable: &str, default: &str| PathBuf::from(std::env::var(variable).unwrap_or_else(|_| default.into()));
    let driver = path("WINDMETA_CHROMEDRIVER", "/usr/bin/chromedriver");
    let chromium = path("WINDMETA_CHROMIUM", "/usr/bin/chromium");
    if driver.exists() && chromium.exists() {
        return Some((driver, chromium));
    }
    let why = format!(
        "no browser: {} and {} are needed (apt install chromium chromium-driver)",
        driver.display(),
        chromium.display()
    );
    crate::harness::unavailable("WINDMETA_REQUIRE_BROWSER", &why);
    None
}

/// A chromedriver process on a free port, stopped when dropped, and the folder the browser
/// saves downloads to.
struct Driver {
    process: Child,
    url: String,
    downloads: PathBuf,
}

impl Driver {
    fn start(path: &Path) -> Driver {
        let port = std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
        let process = Command::new(path)
            .arg(format!("--port={port}"))
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("chromedriver starts");
        let downloads = std::env::temp_dir().join(format!("windmeta-downloads-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&downloads);
        std::fs::create_dir_all(&downloads).unwrap();
        Driver { process, url: format!("http://127.0.0.1:{port}"), downloads }
    }

    async fn open(&self, chromium: &Path) -> Client {
        let mut capabilities = serde_json::Map::new();
        capabilities.insert(
            "goog:chromeOptions".into(),
            json!({
                "binary": chromium,
                "args": ["--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage", "--window-size=1280,800"],
                "prefs": {"download.default_directory": self.downloads, "download.prompt_for_download": false},
            }),
        );
        let started = Instant::now();
        loop {
            let connector = hyper_util::client::legacy::connect::HttpConnector::new();
            match ClientBuilder::new(connector).capabilities(capabilities.clone()).connect(&self.url).await {
                Ok(client) => return client,
                Err(error) if started.elapsed() < Duration::from_secs(20) => {
                    let _ = error;
                    tokio::time::sleep(Duration::from_millis(200)).await;
                }
                Err(error) => panic!("no browser session through chromedriver: {error}"),
            }
        }
    }
}

impl Drop for Driver {
    fn drop(&mut self) {
        let _ = self.process.kill();
        let _ = self.process.wait();
        let _ = std::fs::remove_dir_all(&self.downloads);
    }
}

/// Waits until `condition` (a JavaScript expression) is true on the page; on a timeout, fails with
/// what the page shows as errors and operations.
async fn wait_until(browser: &Client, condition: &str, limit: Duration) {
    let started = Instant::now();
    loop {
        let value = browser.execute(&format!("return Boolean({condition});"), vec![]).await.unwrap();
        if value == Value::Bool(true) {
            return;
        }
        if started.elapsed() > limit {
            let shown = browser
                .execute(
                    "return Array.from(document.querySelectorAll('.error, .status, #operation-list li')).map(e => e.textContent.trim()).filter(Boolean).join(' | ');",
                    vec![],
                )
                .await
                .unwrap();
            panic!("waited {limit:?} for `{condition}`; the page shows: {shown}");
        }
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
}

async fn text_of(browser: &Client, selector: &str) -> String {
    browser.find(Locator::Css(selector)).await.unwrap().text().await.unwrap()
}

async fn set_value(browser: &Client, selector: &str, value: &str) {
    let field = browser.find(Locator::Css(selector)).await.unwrap();
    field.clear().await.unwrap();
    if !value.is_empty() {
        field.send_keys(value).await.unwrap();
    }
}

async fn click(browser: &Client, selector: &str) {
    browser.find(Locator::Css(selector)).await.unwrap().click().await.unwrap();
}

/// Clicks a download link and reads the file the browser saved.
async fn download(browser: &Client, driver: &Driver, selector: &str) -> String {
    let link = browser.find(Locator::Css(selector)).await.unwrap();
    let name = link.attr("download").await.unwrap().expect("a download link names its file");
    let path = driver.downloads.join(&name);
    let _ = std::fs::remove_file(&path);
    link.click().await.unwrap();
    // Chromium writes the download to a `.crdownload` file and renames it over the final name when
    // complete, but may place an empty file under the final name when it starts: the download is
    // done when the file has content and no partial file is left (every download here has content).
    let partial_left = || {
        std::fs::read_dir(&driver.downloads)
            .map(|entries| entries.flatten().any(|e| e.file_name().to_string_lossy().ends_with(".crdownload")))
            .unwrap_or(false)
    };
    let saved = || std::fs::metadata(&path).is_ok_and(|m| m.len() > 0) && !partial_left();
    let started = Instant::now();
    while !saved() {
        assert!(started.elapsed() < Duration::from_secs(20), "{name} was not saved");
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    std::fs::read_to_string(&path).unwrap()
}

/// Rows of numbers from CSV text, the header left out.
fn csv_rows(text: &str) -> Vec<Vec<f64>> {
    text.lines().skip(1).map(|line| line.split(',').map(|v| v.parse().unwrap()).collect()).collect()
}

fn json_rows(answer: &Value) -> Vec<Vec<f64>> {
    let column = |name: &str| answer[name].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect::<Vec<_>>();
    let columns = [column("thresholds"), column("probabilities"), column("lower"), column("upper")];
    (0..columns[0].len()).map(|i| columns.iter().map(|c| c[i]).collect()).collect()
}

fn artefact(name: &str) -> PathBuf {
    let directory = Path::new(env!("CARGO_MANIFEST_DIR")).join("target").join("artifacts");
    std::fs::create_dir_all(&directory).unwrap();
    directory.join(name)
}

/// An engineer's session: key, a refused field, a calibration followed to success, diagnostics, a
/// validation, exceedance curves compared and downloaded, the annual curve, fragility, Sobol
/// indices, a delete; every control labelled; readable on a narrow screen.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_engineer_calibrates_and_explores_in_the_browser() {
    let Some((driver_path, chromium)) = browser() else { return };
    let app = spawn_app_configured(&database("page-browser"), |args| {
        args.api_keys = vec![KEY.into()];
        args.workers = 2;
    })
    .await;
    let driver = Driver::start(&driver_path);
    let browser = driver.open(&chromium).await;
    let long = Duration::from_secs(240);
    let short = Duration::from_secs(20);

    browser.goto(&format!("{}/", app.address)).await.unwrap();
    // Without a key the API refuses, and the page asks for one.
    wait_until(&browser, "!document.querySelector('#key-form').hidden", short).await;
    assert!(text_of(&browser, "#key-status").await.contains("API key"));
    set_value(&browser, "#api-key", KEY).await;
    click(&browser, "#key-form button").await;
    wait_until(&browser, "document.querySelector('#calibration-preset').options.length > 0", short).await;

    // Every control has a label (or an accessible name).
    let unlabelled = browser
        .execute(
            "return Array.from(document.querySelectorAll('input, select, textarea, button')).filter(e => !(e.labels && e.labels.length) && !e.getAttribute('aria-label') && !e.textContent.trim()).map(e => e.id || e.outerHTML);",
            vec![],
        )
        .await
        .unwrap();
    assert_eq!(unlabelled, json!([]), "controls without a label");

    // The server's field error next to its field: more experiments than this server allows (the
    // schema's bound is higher, so only the server can tell).
    set_value(&browser, "#calibration-experiments", &(app.config.max_experiments + 1).to_string()).await;
    click(&browser, "#calibration-form button[type=submit]").await;
    wait_until(&browser, "document.querySelector('#calibration-experiments-error').textContent.length > 0", short)
        .await;
    assert!(text_of(&browser, "#calibration-experiments-error").await.contains("experiments"));
    let invalid =
        browser.find(Locator::Css("#calibration-experiments")).await.unwrap().attr("aria-invalid").await.unwrap();
    assert_eq!(invalid.as_deref(), Some("true"));
    // The advanced box is checked against the schema before anything is sent.
    browser.execute("document.querySelector('#calibration-form details').open = true;", vec![]).await.unwrap();
    set_value(&browser, "#calibration-advanced", r#"{"modes": "three"}"#).await;
    set_value(&browser, "#calibration-experiments", "12").await;
    click(&browser, "#calibration-form button[type=submit]").await;
    wait_until(&browser, "document.querySelector('#calibration-advanced-error').textContent.includes('modes')", short)
        .await;
    assert!(text_of(&browser, "#calibration-experiments-error").await.is_empty(), "the old error is cleared");

    // A small calibration, followed to success.
    set_value(&browser, "#calibration-advanced", "{}").await;
    set_value(&browser, "#calibration-experiments", "24").await;
    set_value(&browser, "#calibration-duration_s", "120").await;
    set_value(&browser, "#calibration-seed", "3").await;
    click(&browser, "#calibration-form button[type=submit]").await;
    wait_until(&browser, "document.querySelector('#operation-list li[data-state]')", short).await;
    let mut progress_seen = String::new();
    let started = Instant::now();
    loop {
        let state = browser
            .execute("const li = document.querySelector('#operation-list li'); return [li.dataset.state, li.querySelector('.progress-text').textContent];", vec![])
            .await
            .unwrap();
        if progress_seen.is_empty() {
            progress_seen = state[1].as_str().unwrap().to_string();
        }
        if state[0] == "succeeded" {
            break;
        }
        assert!(state[0] != "failed" && started.elapsed() < long, "calibration: {state}");
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    eprintln!("progress shown while running: {progress_seen:?}");
    assert!(progress_seen.contains(" of ") || progress_seen.contains("mode"), "no progress shown: {progress_seen:?}");
    let bar = browser
        .execute("const p = document.querySelector('#operation-list li progress'); return [p.value, p.max];", vec![])
        .await
        .unwrap();
    assert_eq!(bar[0], bar[1], "a finished operation's bar is full");
    // The new metamodel is chosen, its diagnostics shown (three modes).
    wait_until(&browser, "!document.querySelector('#metamodel-detail').hidden", short).await;
    wait_until(&browser, "document.querySelectorAll('#diagnostics-table tbody tr').length === 3", short).await;
    let (_, list) = get(&app, "/v1/metamodels").await;
    let metamodel = list["metamodels"][0]["id"].as_str().unwrap().to_string();
    assert!(text_of(&browser, "#metamodel-detail-id").await.contains(&metamodel));

    // A validation from the page: its figures and its scatter of peaks.
    set_value(&browser, "#validation-samples", "6").await;
    click(&browser, "#validation-form button[type=submit]").await;
    wait_until(&browser, "document.querySelectorAll('#validation-chart circle').length === 6", long).await;
    assert!(
        browser
            .execute("return document.querySelectorAll('#validation-table tbody tr').length;", vec![])
            .await
            .unwrap()
            .as_u64()
            .unwrap()
            >= 3
    );

    // An exceedance curve at a wind speed held fixed (the slider stays inside the calibrated range).
    set_value(&browser, "#explore-samples", "300").await;
    click(&browser, "#explore-hold-wind").await;
    let range = browser
        .execute(
            "const s = document.querySelector('#explore-wind'); return [Number(s.min), Number(s.max), s.disabled];",
            vec![],
        )
        .await
        .unwrap();
    assert!(range[0].as_f64().unwrap() < range[1].as_f64().unwrap() && range[2] == false, "{range}");
    let speed = |fraction: f64| {
        let (low, high) = (range[0].as_f64().unwrap(), range[1].as_f64().unwrap());
        ((low + fraction * (high - low)) * 10.0).round() / 10.0
    };
    let set_speed = "const s = document.querySelector('#explore-wind'); s.value = arguments[0]; s.dispatchEvent(new Event('input'));";
    browser.execute(set_speed, vec![json!(speed(0.25))]).await.unwrap();
    click(&browser, "#explore-form button[type=submit]").await;
    wait_until(&browser, "!document.querySelector('#explore-csv').hidden", long).await;
    let csv = download(&browser, &driver, "#explore-csv").await;
    let answer: Value = serde_json::from_str(&download(&browser, &driver, "#explore-json").await).unwrap();
    assert!(csv.starts_with("threshold_m,probability,lower,upper\n"), "{csv}");
    assert_eq!(csv_rows(&csv), json_rows(&answer), "the CSV download's rows are the JSON answer's");
    assert_eq!(answer["samples"], 300);
    // The same request straight to the API, as CSV: the same rows.
    let request = json!({"response": "displacement", "samples": 300, "seed": 1, "confidence": 0.95, "fixed": {"wind_speed": speed(0.25)}});
    let served = app
        .client
        .post(format!("{}/v1/metamodels/{metamodel}/exceedance", app.address))
        .bearer_auth(KEY)
        .header("Accept", "text/csv")
        .json(&request)
        .send()
        .await
        .unwrap()
        .text()
        .await
        .unwrap();
    assert_eq!(csv_rows(&served), json_rows(&answer), "the page's CSV is the API's");
    let table_rows =
        browser.execute("return document.querySelectorAll('#explore-table tbody tr').length;", vec![]).await.unwrap();
    assert_eq!(table_rows.as_u64().unwrap() as usize, json_rows(&answer).len());
    let svg = download(&browser, &driver, "#explore-svg").await;
    assert!(svg.contains("<svg") && svg.contains("polyline"), "the SVG download is the chart");

    // Another input held, at a value outside its law's support: the refusal names it.
    browser.execute("document.querySelector('#explore-form details').open = true;", vec![]).await.unwrap();
    click(&browser, "#explore-hold-damping_ratio").await;
    set_value(&browser, "#explore-held-damping_ratio", "-1").await;
    click(&browser, "#explore-form button[type=submit]").await;
    // The server refuses it before queuing anything; the page shows why next to the held value.
    let refused = "document.querySelector('#explore-held-damping_ratio-error').textContent.includes('fixed.damping_ratio') \
                   && document.querySelector('#explore-held-damping_ratio').getAttribute('aria-invalid') === 'true'";
    wait_until(&browser, refused, short).await;
    click(&browser, "#explore-hold-damping_ratio").await;
    browser.execute("document.querySelector('#explore-form details').open = false;", vec![]).await.unwrap();

    // The values under the keyboard's cursor, then a second curve overlaid on the first.
    let chart = browser.find(Locator::Css("#explore-chart svg")).await.unwrap();
    chart.send_keys(&String::from(char::from(Key::Right))).await.unwrap();
    wait_until(&browser, "document.querySelector('#explore-chart svg').textContent.includes('P = ')", short).await;
    click(&browser, "#explore-keep").await;
    browser.execute(set_speed, vec![json!(speed(0.9))]).await.unwrap();
    click(&browser, "#explore-form button[type=submit]").await;
    let both = format!(
        "document.querySelectorAll('#explore-chart polyline[data-series]').length === 2 && document.querySelector('#explore-chart svg').textContent.includes('{} m/s')",
        speed(0.9)
    );
    wait_until(&browser, &both, long).await;
    let slower: Value = serde_json::from_str(&download(&browser, &driver, "#explore-json").await).unwrap();
    let median = |a: &Value| {
        let rows = json_rows(a);
        rows.iter().find(|r| r[1] <= 0.5).map(|r| r[0]).unwrap()
    };
    assert!(
        median(&slower) > median(&answer),
        "a faster wind gives larger peaks: {} vs {}",
        median(&slower),
        median(&answer)
    );
    browser.execute("document.querySelector('#explore').scrollIntoView();", vec![]).await.unwrap();
    browser.screenshot().await.map(|png| std::fs::write(artefact("page.png"), png).unwrap()).unwrap();

    // Certified with reference storms: more than the storms is refused by the server, naming the
    // field; then the certified curve beside the metamodel's own, and their columns in the table.
    click(&browser, "#explore-clear").await;
    set_value(&browser, "#explore-certify", "301").await;
    click(&browser, "#explore-form button[type=submit]").await;
    wait_until(
        &browser,
        "document.querySelector('#explore-certify-error').textContent.includes('certify.reference_storms')",
        short,
    )
    .await;
    set_value(&browser, "#explore-certify", "16").await;
    click(&browser, "#explore-form button[type=submit]").await;
    let certified = "document.querySelectorAll('#explore-chart polyline[data-series]').length === 2 \
                     && document.querySelector('#explore-chart svg').textContent.includes('metamodel alone')";
    wait_until(&browser, certified, long).await;
    let certified: Value = serde_json::from_str(&download(&browser, &driver, "#explore-json").await).unwrap();
    assert_eq!(certified["certification"]["reference_storms"], 16, "{certified}");
    let mismatch = browser
        .execute("return document.querySelector('#explore-table tbody tr').cells[5].textContent;", vec![])
        .await
        .unwrap();
    assert_ne!(mismatch, json!("—"), "the table shows the mismatch rate");
    set_value(&browser, "#explore-certify", "").await;

    // The annual curve with return levels, fragility over speed, Sobol indices.
    // A site climate needs both speeds (the page says so), speeds that grow with the return
    // period (the server says so, next to the climate), then answers with the limit's β.
    set_value(&browser, "#hazard-samples", "500").await;
    set_value(&browser, "#hazard-speed-50", "31").await;
    click(&browser, "#hazard-form button[type=submit]").await;
    wait_until(&browser, "document.querySelector('#hazard-climate-error').textContent.includes('both')", short).await;
    set_value(&browser, "#hazard-speed-700", "29").await;
    click(&browser, "#hazard-form button[type=submit]").await;
    wait_until(&browser, "document.querySelector('#hazard-climate-error').textContent.includes('grow')", short).await;
    set_value(&browser, "#hazard-speed-700", "33").await;
    set_value(&browser, "#hazard-limit", "0.2").await;
    click(&browser, "#hazard-form button[type=submit]").await;
    wait_until(&browser, "document.querySelectorAll('#hazard-table tbody tr').length >= 3", long).await;
    let notes = text_of(&browser, "#hazard-notes").await + &text_of(&browser, "#hazard-reliability").await;
    assert!(
        notes.to_lowercase().contains("gumbel") && notes.contains("At the limit 0.2 m") && notes.contains("β ="),
        "{notes}"
    );
    // The 1-year level is offered, and the part of the curve from extrapolated speeds is drawn.
    assert_eq!(text_of(&browser, "#hazard-table tbody tr:first-child td:first-child").await, "1 year");
    let series = "return document.querySelectorAll('#hazard-chart polyline[data-series]').length;";
    assert_eq!(browser.execute(series, vec![]).await.unwrap(), json!(2));
    // Certified over the wind strata: the certified curve beside the metamodel's own.
    set_value(&browser, "#hazard-certify", "40").await;
    click(&browser, "#hazard-form button[type=submit]").await;
    let certified = "document.querySelectorAll('#hazard-chart polyline[data-series]').length === 3 \
                     && document.querySelector('#hazard-chart svg').textContent.includes('metamodel alone')";
    wait_until(&browser, certified, long).await;
    set_value(&browser, "#hazard-certify", "").await;
    set_value(&browser, "#fragility-samples", "20").await;
    set_value(&browser, "#fragility-thresholds", "0.4, 0.6").await;
    click(&browser, "#fragility-form button[type=submit]").await;
    wait_until(&browser, "document.querySelectorAll('#fragility-chart polyline[data-series]').length === 2", long)
        .await;
    // Certified at each speed: each threshold's certified curve beside the metamodel's own.
    set_value(&browser, "#fragility-certify", "8").await;
    click(&browser, "#fragility-form button[type=submit]").await;
    let certified = "document.querySelectorAll('#fragility-chart polyline[data-series]').length === 4 \
                     && document.querySelector('#fragility-chart svg').textContent.includes('metamodel alone')";
    wait_until(&browser, certified, long).await;
    // The serviceability check: a typed criterion that is not JSON is named before sending, one
    // the server refuses is named with its field; built-ins and a typed RMS criterion in milli-g
    // answer a table of verdicts and the profiles over their limits (three criteria and the limit).
    set_value(&browser, "#serviceability-samples", "400").await;
    set_value(&browser, "#serviceability-criteria", "[{").await;
    click(&browser, "#serviceability-form button[type=submit]").await;
    wait_until(
        &browser,
        "document.querySelector('#serviceability-criteria-error').textContent.includes('JSON')",
        short,
    )
    .await;
    let typed = r#"[{"name": "roof rms", "response": "acceleration", "statistic": "rms", "return_period_years": 1, "limit_milli_g": 5, "floors": [38, 40]}]"#;
    set_value(&browser, "#serviceability-criteria", &typed.replace("[38, 40]", "[0, 40]")).await;
    click(&browser, "#serviceability-form button[type=submit]").await;
    // After the two built-ins checked by default, the typed criterion is the third.
    let refused = "document.querySelector('#serviceability-criteria-error').textContent.includes('criteria[2].floors')";
    wait_until(&browser, refused, long).await;
    set_value(&browser, "#serviceability-criteria", typed).await;
    click(&browser, "#serviceability-form button[type=submit]").await;
    wait_until(&browser, "document.querySelectorAll('#serviceability-table tbody tr').length === 3", long).await;
    let verdicts =
        "return [...document.querySelectorAll('#serviceability-table tbody tr')].map((r) => r.dataset.verdict);";
    let verdicts = browser.execute(verdicts, vec![]).await.unwrap();
    assert!(
        verdicts.as_array().unwrap().iter().all(|v| ["pass", "fail", "inconclusive"].contains(&v.as_str().unwrap())),
        "{verdicts}"
    );
    let rms_row = text_of(&browser, "#serviceability-table tbody tr:last-child").await;
    assert!(rms_row.contains("roof rms") && rms_row.contains("0.04903"), "5 milli-g in m/s²: {rms_row}");
    let profiles = "return document.querySelectorAll('#serviceability-chart polyline[data-series]').length;";
    assert_eq!(browser.execute(profiles, vec![]).await.unwrap(), json!(4));
    browser.execute("document.querySelector('#serviceability-table').scrollIntoView();", vec![]).await.unwrap();
    browser.screenshot().await.map(|png| std::fs::write(artefact("page-serviceability.png"), png).unwrap()).unwrap();
    // The sweep of a damper group's coefficient: one point per value.
    set_value(&browser, "#sweep-samples", "200").await;
    set_value(&browser, "#sweep-values", "0, 50000, 100000").await;
    browser.execute("document.querySelector('#sweep-input').value = 'damper_c4';", vec![]).await.unwrap();
    click(&browser, "#sweep-form button[type=submit]").await;
    wait_until(&browser, "document.querySelectorAll('#sweep-chart circle').length === 3", long).await;
    set_value(&browser, "#sweep-values", "-5").await;
    click(&browser, "#sweep-form button[type=submit]").await;
    wait_until(&browser, "document.querySelector('#sweep-values-error').textContent.includes('support')", long).await;
    set_value(&browser, "#sensitivity-samples", "64").await;
    click(&browser, "#sensitivity-form button[type=submit]").await;
    wait_until(&browser, "document.querySelectorAll('#sensitivity-table tbody tr').length >= 5", long).await;
    // A bad value the server refuses is shown next to its field.
    set_value(&browser, "#sensitivity-floor", "999").await;
    click(&browser, "#sensitivity-form button[type=submit]").await;
    wait_until(&browser, "document.querySelector('#sensitivity-floor-error').textContent.includes('floor')", short)
        .await;
    browser.screenshot().await.map(|png| std::fs::write(artefact("page-analyses.png"), png).unwrap()).unwrap();

    // A narrow screen: nothing wider than the window.
    browser.set_window_size(420, 900).await.unwrap();
    let overflow =
        browser.execute("return document.documentElement.scrollWidth - window.innerWidth;", vec![]).await.unwrap();
    assert!(overflow.as_f64().unwrap() <= 0.0, "the page is {overflow} px wider than a narrow window");
    browser.screenshot().await.map(|png| std::fs::write(artefact("page-narrow.png"), png).unwrap()).unwrap();
    browser.set_window_size(1280, 800).await.unwrap();

    // Delete, after a confirmation.
    click(&browser, "#metamodel-delete").await;
    browser.accept_alert().await.unwrap();
    wait_until(&browser, "document.querySelector('#metamodel-detail').hidden", short).await;
    let (_, list) = get(&app, "/v1/metamodels").await;
    assert_eq!(list["metamodels"], json!([]));

    // A long calibration, cancelled from its row: the form says so.
    set_value(&browser, "#calibration-experiments", "200").await;
    set_value(&browser, "#calibration-duration_s", "900").await;
    click(&browser, "#calibration-form button[type=submit]").await;
    wait_until(&browser, "document.querySelector('#operation-list li[data-state=running] .cancel')", long).await;
    click(&browser, "#operation-list li[data-state=running] .cancel").await;
    wait_until(&browser, "document.querySelector('#operation-list li[data-state=cancelled]')", long).await;
    wait_until(&browser, "document.querySelector('#calibration-error').textContent.includes('cancelled')", short).await;

    browser.close().await.unwrap();
    drop(driver);
    app.stop().await;
}

async fn get(app: &TestApp, path: &str) -> (u16, Value) {
    let response = app.client.get(format!("{}{path}", app.address)).bearer_auth(KEY).send().await.unwrap();
    (response.status().as_u16(), response.json().await.unwrap())
}
