//! The service's edge against a hostile client, over real HTTP: keys that cannot be empty, every
//! cost-driving field refused before anything is queued, bodies that are not objects, bounded
//! synchronous sampling (permits, timeout, a client that leaves), a cache that cannot undo a
//! delete, idempotency keys that expire, bodies far over the limit answered 413 that the client
//! reads.

use crate::harness::app::{TestApp, assert_problem, database, problem_details, spawn_app, spawn_app_configured};
use crate::harness::fixture;
use serde_json::{Value, json};
use std::process::Command;
use std::time::{Duration, Instant};
use windmeta::error::Error;
use windmeta::service::{Application, ServeArgs};

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn empty_or_blank_api_keys_are_refused_at_start_up() {
    for keys in [vec!["k1", ""], vec![""], vec!["k1", "  "]] {
        let args = ServeArgs {
            listen: "127.0.0.1:0".into(),
            database_url: format!("sqlite://{}", database("keys").display()),
            api_keys: keys.iter().map(|k| k.to_string()).collect(),
            ..ServeArgs::default()
        };
        match Application::build(args).await {
            Err(Error::Invalid { field, .. }) => assert!(field.starts_with("api_keys["), "{keys:?}: {field}"),
            Err(other) => panic!("{keys:?}: {other}"),
            Ok(_) => panic!("{keys:?}: the server started"),
        }
    }
    // The command line as a user types it: a trailing comma in the environment variable.
    let output = Command::new(env!("CARGO_BIN_EXE_windmeta"))
        .args(["serve", "--listen", "127.0.0.1:0"])
        .env("WINDMETA_API_KEYS", "k1,")
        .env("DATABASE_URL", format!("sqlite://{}", database("keys-cli").display()))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("api_keys[1]") && stderr.contains("empty"), "{stderr}");
    // An unreachable database is not bad input: its own exit code, and a message that names the
    // database without its password (start-up errors end up in logs).
    for url in ["postgres://nobody:hunter2@127.0.0.1:1/none", "postgres://nobody@127.0.0.1:1/none?password=hunter2"] {
        let output = Command::new(env!("CARGO_BIN_EXE_windmeta"))
            .args(["serve", "--listen", "127.0.0.1:0", "--database-url", url])
            .env_remove("WINDMETA_API_KEYS")
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(3), "{stderr}");
        assert!(stderr.contains("127.0.0.1:1/none") && !stderr.contains("hunter2"), "{stderr}");
    }
    // A SQLite file in a folder it cannot create or write (a container's bind mount owned by
    // another user, as a rule): the message says which folder and what it needs.
    let output = Command::new(env!("CARGO_BIN_EXE_windmeta"))
        .args(["serve", "--listen", "127.0.0.1:0", "--database-url", "sqlite:///proc/windmeta-nowhere/windmeta.db"])
        .env_remove("WINDMETA_API_KEYS")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(3), "{stderr}");
    assert!(stderr.contains("the folder /proc/windmeta-nowhere must exist and be writable"), "{stderr}");
}

/// Every request below would have cost time or memory without bound; each is refused with the
/// field named, and nothing is queued.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn costly_calibrations_are_refused_before_anything_is_queued() {
    let app = spawn_app(&database("costly")).await;
    let cases: Vec<(Value, &str)> = vec![
        (
            json!({"preset": "frame40-kn", "experiments": 20, "duration_s": 60, "wind": {"field_generation_step_s": 1e-7}}),
            "wind.field_generation_step_s",
        ),
        (json!({"wind": {"frequencies": 65536, "field_generation_step_s": 0.001}}), "wind.field_generation_step_s"),
        (json!({"wind": {"frequencies": 70000}}), "wind.frequencies"),
        (json!({"wind": {"cutoff_rad_s": 1e6}}), "wind.cutoff_rad_s"),
        (json!({"wind": {"cutoff_rad_s": -1}}), "wind.cutoff_rad_s"),
        (json!({"duration_s": 1e9}), "duration_s"),
        (json!({"duration_s": 86400, "time_step_s": 0.01}), "duration_s"),
        (json!({"duration_s": 3000, "modes": 1}), "duration_s"),
        (json!({"time_step_s": 1e-7}), "time_step_s"),
        (json!({"modes": 11}), "modes"),
        (json!({"modes": 4000000000u64}), "modes"),
        (json!({"experiments": 1_000_000_000}), "experiments"),
        (json!({"narx": {"max_terms": 10000}}), "narx.max_terms"),
        (json!({"narx": {"output_lags": 1000}}), "narx.output_lags"),
        (json!({"pce": {"max_degree": 1000}}), "pce.max_degree"),
        (json!({"pce": {"max_interaction": 8}}), "pce"),
        (json!({"pce": {"lars_early_stop": 1_000_000_000}}), "pce.lars_early_stop"),
        (json!({"pce": {"q_norm": 0}}), "pce.q_norm"),
        (json!({"damper_exponent": 1e300}), "damper_exponent"),
        (json!({"inputs": {"x": {"distribution": "constant", "value": 1}}}), "unknown input"),
        (
            json!({"structure": {"mass": [[1e5]], "stiffness": [[1e8]], "floor_elevations_m": (1..=201).collect::<Vec<_>>(), "floor_widths_m": [20]}}),
            "floor_elevations_m",
        ),
        (
            json!({"structure": {"mass": [[1e5]], "stiffness": [[1e8]], "floor_elevations_m": [4], "floor_widths_m": [20],
            "dampers": [{"floor": 1, "group": 11, "cos_angle": 1}]}}),
            "dampers[0].group",
        ),
        (json!([]), "body"),
        (json!([{"preset": "frame40-kn"}]), "body"),
        (Value::Null, "body"),
        (json!(1), "body"),
        (json!("frame40-kn"), "body"),
        (json!(true), "body"),
    ];
    for (body, field) in cases {
        let started = Instant::now();
        let (s, ct, answer) = problem_details(app.post("/v1/calibrations", body.clone()).await).await;
        assert_problem(s, &ct, &answer, 422, field);
        assert!(started.elapsed() < Duration::from_secs(10), "{body}: took {:?}", started.elapsed());
    }
    let (_, list) = app.get("/v1/operations").await;
    assert_eq!(list["operations"], json!([]), "something was queued");
    app.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn hostile_sampling_requests_are_refused_and_a_delete_sticks() {
    let app = spawn_app(&database("sampling")).await;
    let id = fixture::install(&app, fixture::STORM_S).await;
    let path = format!("/v1/metamodels/{id}/exceedance");
    let cases: Vec<(Value, &str)> = vec![
        (json!({"thresholds": [-1e308, 1e308]}), "thresholds"),
        (json!({"thresholds": [0.1, f64::MAX]}), "thresholds"),
        (json!({"thresholds": vec![0.1; 10_001]}), "thresholds"),
        (json!({"thresholds": []}), "thresholds"),
        (json!({"samples": 1_000_000_000_000u64}), "samples"),
        (json!({"samples": 0}), "samples"),
        (json!({"floor": 0}), "floor"),
        (json!({"floor": 41}), "floor"),
        (json!({"floor": 1_000_000}), "floor"),
        (json!({"confidence": 1.5}), "confidence"),
        (json!({"fixed": {"wind_speed": 1e308}}), "fixed.wind_speed"),
        (json!({"fixed": {"x": 1}}), "unknown input"),
        (json!([]), "body"),
    ];
    for (body, field) in cases {
        let r = app.client.post(format!("{}{path}", app.address)).header("accept", "image/svg+xml").json(&body);
        let (s, ct, answer) = problem_details(r.send().await.unwrap()).await;
        assert_problem(s, &ct, &answer, 422, field);
    }
    let validation = format!("/v1/metamodels/{id}/validations");
    let (s, ct, answer) = problem_details(app.post(&validation, json!({"samples": 1_000_000})).await).await;
    assert_problem(s, &ct, &answer, 422, "samples");

    // Loaded into the cache by the requests above; deleted; not served again.
    assert_eq!(app.post(&path, json!({"samples": 16})).await.status().as_u16(), 200);
    let deleted = app.client.delete(format!("{}/v1/metamodels/{id}", app.address)).send().await.unwrap();
    assert_eq!(deleted.status().as_u16(), 204);
    let (s, ct, answer) = problem_details(app.post(&path, json!({"samples": 16})).await).await;
    assert_problem(s, &ct, &answer, 404, &id);
    app.stop().await;
}

/// A body far over the limit (a thousand times the test server's 64 KiB) is answered 413
/// problem+json that the client reads after sending all of it, with a declared length and chunked;
/// a client that waits for `100 Continue` gets the 413 instead and sends nothing.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_body_far_over_the_limit_is_answered_413_that_the_client_reads() {
    use tokio::io::{AsyncReadExt, AsyncWriteExt};
    let app = spawn_app(&database("oversized")).await;
    let host = app.address.trim_start_matches("http://").to_string();
    let body = vec![b' '; 64 * 1024 * 1000];
    for framing in ["content-length", "chunked", "expect"] {
        let mut stream = tokio::net::TcpStream::connect(&host).await.unwrap();
        let head = match framing {
            "chunked" => "transfer-encoding: chunked\r\n".to_string(),
            "expect" => format!("content-length: {}\r\nexpect: 100-continue\r\n", body.len()),
            _ => format!("content-length: {}\r\n", body.len()),
        };
        let request =
            format!("POST /v1/calibrations HTTP/1.1\r\nhost: {host}\r\ncontent-type: application/json\r\n{head}\r\n");
        stream.write_all(request.as_bytes()).await.unwrap();
        let (mut reader, mut writer) = stream.into_split();
        // The writing half is handed back, not dropped: dropping it would half-close the
        // connection, which an HTTP/1.1 server may take for the client leaving before it has
        // read the body's end (hyper does, and then drops the request: an empty answer).
        let sending = {
            let body = body.clone();
            tokio::spawn(async move {
                match framing {
                    "expect" => {}
                    "chunked" => {
                        for chunk in body.chunks(1 << 20) {
                            writer.write_all(format!("{:x}\r\n", chunk.len()).as_bytes()).await?;
                            writer.write_all(chunk).await?;
                            writer.write_all(b"\r\n").await?;
                        }
                        writer.write_all(b"0\r\n\r\n").await?;
                    }
                    _ => writer.write_all(&body).await?,
                }
                std::io::Result::Ok(writer)
            })
        };
        let mut answer = Vec::new();
        tokio::time::timeout(Duration::from_secs(60), reader.read_to_end(&mut answer)).await.unwrap().unwrap();
        let sent = sending.await.unwrap();
        assert!(sent.is_ok(), "{framing}: the body could not be sent whole: {sent:?}");
        let answer = String::from_utf8_lossy(&answer).to_lowercase();
        assert!(answer.starts_with("http/1.1 413"), "{framing}: {answer}");
        assert!(answer.contains("content-type: application/problem+json"), "{framing}: {answer}");
        assert!(answer.contains("connection: close"), "{framing}: {answer}");
        assert!(answer.contains("request body too large"), "{framing}: {answer}");
    }
    app.stop().await;
}

/// Sampling a 900 s metamodel 20 000 times takes seconds on 2 cores: long enough to hold the one
/// permit, to run past a 1 s timeout, and for a client to leave in the middle.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn synchronous_sampling_is_bounded_timed_out_and_stopped_when_the_client_leaves() {
    let db = database("permits");
    let app = spawn_app_configured(&db, |args| {
        args.max_sync_requests = 1;
        args.sync_timeout_s = 1;
        args.max_samples = 20_000;
        args.max_sync_samples = 20_000;
    })
    .await;
    let id = fixture::install(&app, 900.0).await;
    let url = format!("{}/v1/metamodels/{id}/exceedance", app.address);
    let long = json!({"samples": 20_000});
    let small = json!({"samples": 8});

    let client = app.client.clone();
    let (first_url, first_body) = (url.clone(), long.clone());
    let started = Instant::now();
    let first = tokio::spawn(async move { client.post(first_url).json(&first_body).send().await.unwrap() });
    tokio::time::sleep(Duration::from_millis(300)).await;
    let busy = app.client.post(&url).json(&small).send().await.unwrap();
    assert_eq!(busy.status().as_u16(), 503);
    assert!(busy.headers().contains_key("retry-after"));
    let first = first.await.unwrap();
    let waited = started.elapsed();
    let (s, ct, answer) = problem_details(first).await;
    assert_problem(s, &ct, &answer, 503, "not answered within 1 s");
    assert!(waited < Duration::from_secs(3), "the timeout took {waited:?}");
    // The timed-out sampling stopped, so its permit comes back at once.
    let freed = permit_returns(&app, &url).await;
    assert!(freed < Duration::from_secs(1), "sampling went on for {freed:?} after the timeout");
    app.stop().await;

    // A client that gives up: the server stops sampling for it (no timeout to help here).
    let app = spawn_app_configured(&db, |args| {
        args.max_sync_requests = 1;
        args.max_samples = 20_000;
        args.max_sync_samples = 20_000;
    })
    .await;
    let impatient = reqwest::Client::builder().timeout(Duration::from_millis(300)).build().unwrap();
    let url = format!("{}/v1/metamodels/{id}/exceedance", app.address);
    assert!(impatient.post(&url).json(&long).send().await.is_err());
    let freed = permit_returns(&app, &url).await;
    assert!(freed < Duration::from_secs(1), "sampling went on for {freed:?} after the client left");
    app.stop().await;
}

/// How long until a small synchronous request is answered again (the only permit is back).
async fn permit_returns(app: &TestApp, url: &str) -> Duration {
    let since = Instant::now();
    while since.elapsed() < Duration::from_secs(10) {
        let status = app.client.post(url).json(&json!({"samples": 8})).send().await.unwrap().status();
        if status.as_u16() == 200 {
            eprintln!("permit back after {:.0} ms", since.elapsed().as_secs_f64() * 1e3);
            return since.elapsed();
        }
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    panic!("the permit did not come back");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn idempotency_keys_expire() {
    let app = spawn_app_configured(&database("expiry"), |args| args.idempotency_ttl_h = 0).await;
    let url = format!("{}/v1/calibrations", app.address);
    let body = json!({"experiments": 4, "duration_s": 10});
    let send = || app.client.post(&url).header("idempotency-key", "k").json(&body).send();
    let first = send().await.unwrap().headers()["location"].clone();
    let second = send().await.unwrap().headers()["location"].clone();
    assert_ne!(first, second, "an expired key replayed the operation");
    app.stop().await;
}

/// A malformed Idempotency-Key (the contract's pattern: 1 to 255 visible ASCII characters) is
/// refused whether the request would be queued or answered at once, and nothing is queued.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn malformed_idempotency_keys_are_refused_queued_or_not() {
    let app = spawn_app(&database("malformed-key")).await;
    let id = fixture::install(&app, fixture::STORM_S).await;
    let exceedance = format!("/v1/metamodels/{id}/exceedance");
    for (path, body) in
        [("/v1/calibrations", json!({"experiments": 4, "duration_s": 10})), (&exceedance, json!({"samples": 8}))]
    {
        for key in ["two words", "", &"k".repeat(256)] {
            let asked = app.client.post(format!("{}{path}", app.address)).header("idempotency-key", key).json(&body);
            let (s, ct, problem) = problem_details(asked.send().await.unwrap()).await;
            assert_problem(s, &ct, &problem, 422, "Idempotency-Key");
        }
    }
    let (_, list) = app.get("/v1/operations").await;
    assert_eq!(list["operations"].as_array().map(Vec::len), Some(0), "{list}");
    app.stop().await;
}
