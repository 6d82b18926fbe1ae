//! The checks a design office signs and the sweeps that size its dampers, on the shared fixture:
//! a serviceability criterion that asks what an annual curve asks answers the curve's level
//! exactly, a sweep holds its input while the storms stay the same, and both routes answer the
//! library's numbers and refuse bad input naming the field.

use crate::harness::app::{assert_problem, database, problem_details, spawn_app};
use crate::harness::fixture;
use serde_json::{Value, json};
use windmeta::analysis::{
    CertifyOptions, Criterion, DEFAULT_RETURN_PERIODS, HazardOptions, OnThisMachine, Response, ResponseKind,
    ReturnLevel, Sampling, ServiceabilityOptions, Statistic, SweepOptions, Verdict, metamodel_hazard,
    metamodel_serviceability, metamodel_sweep,
};
use windmeta::progress::Silent;
use windmeta::study::Order;
use windmeta::uncertainty::Marginal;

const CLIMATE: Marginal = Marginal::Gumbel { location: 25.0, scale: 2.5 };

fn roof_acceleration(limit: f64) -> Criterion {
    Criterion {
        name: "roof".into(),
        response: ResponseKind::Acceleration,
        statistic: Statistic::Peak,
        return_period_years: 10.0,
        limit: Some(limit),
        limit_per_storey_height: None,
        floors: Some([40, 40]),
        strength: None,
    }
}

/// The fixture's 10-year roof acceleration from its annual curve under [`CLIMATE`].
fn roof_acceleration_level(samples: usize, seed: u64, certify: Option<CertifyOptions>) -> ReturnLevel {
    let (metamodel, study) = fixture::metamodel();
    let hazard = HazardOptions {
        climate: CLIMATE,
        samples,
        seed,
        thresholds: None,
        return_periods: vec![10.0],
        limit: None,
        confidence: 0.95,
        sampling: Sampling::Stratified,
        certify,
    };
    let roof = Response::Acceleration { floor: 40 };
    let curve = metamodel_hazard(metamodel, study, roof, &hazard, &OnThisMachine, &Silent).unwrap();
    curve.return_levels[0].clone()
}

/// One criterion at the roof's 10-year level aims the strata where an annual curve asking for the
/// 10-year level aims them (Neyman's scores doubled are the same allocation), so it draws the same
/// storms and must find the same level and band, to rounding; limits on either side of the band
/// give `pass` and `fail`.
#[test]
fn a_criterion_finds_the_annual_curves_level() {
    let (metamodel, study) = fixture::metamodel();
    let (samples, seed) = (400, 5);
    let level = roof_acceleration_level(samples, seed, None);
    let (value, lower, upper) = (level.value.unwrap(), level.lower.unwrap(), level.upper.unwrap());
    let check = |limit: f64| {
        let options = ServiceabilityOptions {
            climate: CLIMATE,
            criteria: vec![roof_acceleration(limit)],
            samples,
            seed,
            confidence: 0.95,
            certify: None,
        };
        metamodel_serviceability(metamodel, study, &options, &OnThisMachine, &Silent).unwrap().criteria.remove(0)
    };
    let judged = check(2.0 * upper);
    for (got, want) in [(judged.value, value), (judged.lower, lower), (judged.upper, upper)] {
        assert!((got.unwrap() / want - 1.0).abs() < 1e-12, "{got:?} vs {want}");
    }
    assert_eq!((judged.governing_floor, judged.verdict), (40, Verdict::Pass));
    assert_eq!(check(0.5 * lower).verdict, Verdict::Fail);
    assert_eq!(check(value).verdict, Verdict::Inconclusive);
    assert!(DEFAULT_RETURN_PERIODS.contains(&10.0));
}

/// Certified, the criterion's governing floor is the certified annual curve's: the same reference
/// storms (one seed, the allocation aimed at the same level) correct the same metamodel sample, so
/// the certified level and band are the curve's to rounding, and the metamodel's own are kept.
#[test]
fn a_certified_criterion_finds_the_certified_curves_level() {
    let (metamodel, study) = fixture::metamodel();
    let (samples, seed) = (400, 5);
    let certify = Some(CertifyOptions { reference_storms: 40, order: Order::Reduced });
    let level = roof_acceleration_level(samples, seed, certify);
    let options = ServiceabilityOptions {
        climate: CLIMATE,
        criteria: vec![roof_acceleration(1.0)],
        samples,
        seed,
        confidence: 0.95,
        certify,
    };
    let judged =
        metamodel_serviceability(metamodel, study, &options, &OnThisMachine, &Silent).unwrap().criteria.remove(0);
    for (got, want) in [(judged.value, level.value), (judged.lower, level.lower), (judged.upper, level.upper)] {
        assert!((got.unwrap() / want.unwrap() - 1.0).abs() < 1e-12, "{got:?} vs {want:?}");
    }
    let c = judged.certification.unwrap();
    assert_eq!((c.floor, c.reference_storms), (40, 40));
    assert!(c.metamodel_value.is_some() && judged.profile.values[0] == judged.value);
}

/// Over HTTP the check and the sweep are the library's; CSV and SVG by `Accept`; more damping in
/// the top group lowers the roof's 10-year acceleration (the same storms at every value, so the
/// order is the dampers', not noise); bad input is refused naming the field.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_design_routes_answer_the_librarys_numbers() {
    let app = spawn_app(&database("design")).await;
    let id = fixture::install(&app, fixture::STORM_S).await;
    let (metamodel, study) = fixture::metamodel();
    let climate = json!({"distribution": "gumbel", "location": 25.0, "scale": 2.5});

    let path = format!("/v1/metamodels/{id}/serviceability");
    let request = json!({"climate": climate, "criteria": ["nbcc-office", "drift-h400"], "samples": 300, "seed": 2});
    let (status, served) = app.post_json(&path, request.clone()).await;
    assert_eq!(status, 200, "{served}");
    let floors = study.structure.floors();
    let criteria = ["nbcc-office", "drift-h400"].map(|name| windmeta::analysis::built_in(name, floors).unwrap());
    let options = ServiceabilityOptions {
        climate: CLIMATE,
        criteria: criteria.to_vec(),
        samples: 300,
        seed: 2,
        confidence: 0.95,
        certify: None,
    };
    let here = tokio::task::block_in_place(|| {
        metamodel_serviceability(metamodel, study, &options, &OnThisMachine, &Silent).unwrap()
    });
    assert_eq!(served["criteria"], serde_json::to_value(&here.criteria).unwrap());
    assert_eq!(served["metamodel_id"], id.as_str());
    assert_eq!(served["criteria"][0]["profile"]["floors"].as_array().unwrap().len(), 10);
    assert_eq!(served["criteria"][1]["profile"]["floors"].as_array().unwrap().len(), floors);
    for (accept, media) in [("text/csv", "text/csv"), ("image/svg+xml", "image/svg+xml")] {
        let response = app.client.post(format!("{}{path}", app.address)).header("accept", accept).json(&request);
        let response = response.send().await.unwrap();
        assert_eq!((response.status().as_u16(), response.headers()["content-type"].to_str().unwrap()), (200, media));
        let body = response.text().await.unwrap();
        if media == "text/csv" {
            assert_eq!(body, here.csv());
        }
    }
    let criterion = |change: Value| {
        let mut c = json!({"name": "c", "response": "drift", "return_period_years": 10, "limit": 0.01});
        c.as_object_mut().unwrap().extend(change.as_object().unwrap().clone());
        json!({"criteria": [c], "samples": 300})
    };
    for (wrong, field) in [
        (json!({"criteria": ["comfy"]}), "criteria"),
        (json!({"criteria": []}), "criteria"),
        (criterion(json!({"floors": [0, 3]})), "criteria[0].floors"),
        (criterion(json!({"floors": [3, 41]})), "criteria[0].floors"),
        (criterion(json!({"return_period_years": 0.5})), "criteria[0].return_period_years"),
        (criterion(json!({"limit": -1})), "criteria[0].limit"),
        (criterion(json!({"statistic": "rms"})), "criteria[0].statistic"),
        (json!({"samples": 2_000_000}), "samples"),
    ] {
        let (status, content_type, body) = problem_details(app.post(&path, wrong.clone()).await).await;
        assert_problem(status, &content_type, &body, 422, field);
    }
    let (status, _, _) = problem_details(app.post(&path, criterion(json!({"response": "sway"}))).await).await;
    assert_eq!(status, 422, "an unknown response is refused");
    // Certified, the check is an operation whose result is the library's certified check.
    let certify = json!({"reference_storms": 40});
    let certified =
        json!({"climate": climate, "criteria": ["nbcc-office"], "samples": 300, "seed": 2, "certify": certify});
    let (status, queued) = app.post_json(&path, certified).await;
    assert_eq!(status, 202, "{queued}");
    let limit = std::time::Duration::from_secs(120);
    let done = app.wait_for(queued["id"].as_str().unwrap(), &["succeeded", "failed"], limit).await;
    assert_eq!(done["state"], "succeeded", "{done}");
    let options = ServiceabilityOptions {
        criteria: criteria[..1].to_vec(),
        certify: Some(CertifyOptions { reference_storms: 40, order: Order::Reduced }),
        ..options.clone()
    };
    let here = tokio::task::block_in_place(|| {
        metamodel_serviceability(metamodel, study, &options, &OnThisMachine, &Silent).unwrap()
    });
    assert_eq!(done["result"]["criteria"], serde_json::to_value(&here.criteria).unwrap());
    assert_eq!(done["result"]["criteria"][0]["certification"]["reference_storms"], 40);

    let path = format!("/v1/metamodels/{id}/sweep");
    let values = [0.0, 50_000.0, 100_000.0];
    let request = json!({"input": "damper_c4", "values": values, "climate": climate, "response": "acceleration",
                         "samples": 200, "seed": 3});
    let (status, served) = app.post_json(&path, request).await;
    assert_eq!(status, 200, "{served}");
    let options = SweepOptions {
        input: "damper_c4".into(),
        values: values.to_vec(),
        climate: CLIMATE,
        return_period_years: 10.0,
        samples: 200,
        seed: 3,
        confidence: 0.95,
    };
    let roof = Response::Acceleration { floor: floors };
    let here = tokio::task::block_in_place(|| {
        metamodel_sweep(metamodel, study, roof, &options, &OnThisMachine, &Silent).unwrap()
    });
    assert_eq!(served["results"], serde_json::to_value(&here.results).unwrap());
    let levels: Vec<f64> = here.results.iter().map(|p| p.level.unwrap()).collect();
    assert!(levels.windows(2).all(|w| w[1] < w[0]), "more damping, less acceleration: {levels:?}");
    let sweep = |change: Value| {
        let mut r = json!({"input": "damper_c4", "values": [0.0], "samples": 200});
        r.as_object_mut().unwrap().extend(change.as_object().unwrap().clone());
        r
    };
    for (wrong, field) in [
        (sweep(json!({"input": "wind_speed"})), "input"),
        (sweep(json!({"input": "colour"})), "input"),
        (sweep(json!({"values": [-1.0]})), "values"),
        (sweep(json!({"values": [1e9]})), "values"),
        (sweep(json!({"values": vec![1.0; 21]})), "values"),
        (sweep(json!({"values": []})), "values"),
        (sweep(json!({"return_period_years": 0.5})), "return_period_years"),
        (sweep(json!({"floor": 41})), "floor"),
        (sweep(json!({"samples": 900_000, "values": [1.0, 2.0]})), "samples"),
    ] {
        let (status, content_type, body) = problem_details(app.post(&path, wrong.clone()).await).await;
        assert_problem(status, &content_type, &body, 422, field);
    }
    app.stop().await;
}

/// The commands as a user runs them: built-ins by name and a criteria file, every format, and bad
/// input refused with exit code 2 naming the field.
#[test]
fn the_design_commands_answer_and_refuse_by_name() {
    let run = |args: &[&str]| std::process::Command::new(env!("CARGO_BIN_EXE_windmeta")).args(args).output().unwrap();
    let dir = std::env::temp_dir().join(format!("windmeta-design-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let model = dir.join("model.json");
    std::fs::write(&model, serde_json::to_string(&fixture::metamodel().0).unwrap()).unwrap();
    let model = model.to_str().unwrap();
    let criteria = dir.join("criteria.json");
    let typed = r#"["nbcc-residential", {"name": "rms", "response": "acceleration", "statistic": "rms",
                    "return_period_years": 1, "limit": 0.05, "floors": [39, 40]}]"#;
    std::fs::write(&criteria, typed).unwrap();
    let criteria = criteria.to_str().unwrap();
    let out = run(&["serviceability", "--model", model, "--criteria-file", criteria, "--samples", "120", "--json"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let answer: Value = serde_json::from_slice(&out.stdout).unwrap();
    let names: Vec<&str> = answer["criteria"].as_array().unwrap().iter().map(|c| c["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["nbcc-residential", "rms"]);
    assert_eq!(answer["criteria"][1]["profile"]["floors"], json!([39, 40]));
    for (file, check) in
        [("check.csv", "criterion,response,statistic"), ("check.svg", "<svg"), ("check.json", "\"verdict\"")]
    {
        let path = dir.join(file);
        let args = ["serviceability", "--model", model, "--criteria", "drift-h400", "--samples", "120", "--out"];
        let out = run(&[&args[..], &[path.to_str().unwrap()]].concat());
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        assert!(std::fs::read_to_string(&path).unwrap().contains(check), "{file}");
    }
    let sweep_csv = dir.join("sweep.csv");
    let sweep = ["sweep", "--model", model, "--input", "damper_c1", "--values", "0,50000", "--samples", "120"];
    let out = run(&[&sweep[..], &["--out", sweep_csv.to_str().unwrap()]].concat());
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(std::fs::read_to_string(&sweep_csv).unwrap().lines().count(), 3, "a header and a row per value");
    let bad_file = dir.join("bad.json");
    std::fs::write(
        &bad_file,
        r#"[{"name": "c", "response": "drift", "return_period_years": 10, "limit": 0.01, "floors": [0, 1]}]"#,
    )
    .unwrap();
    for (args, expected) in [
        (vec!["serviceability", "--model", model, "--criteria", "comfy"], "criteria"),
        (vec!["serviceability", "--model", model, "--criteria-file", bad_file.to_str().unwrap()], "criteria[0].floors"),
        (vec!["serviceability", "--model", model, "--criteria-file", "missing.json"], "criteria_file"),
        (vec!["serviceability", "--model", model, "--criteria", "nbcc-office", "--climate", "{}"], "climate"),
        (vec!["sweep", "--model", model, "--input", "wind_speed", "--values", "30"], "input"),
        (vec!["sweep", "--model", model, "--input", "damper_c1", "--values", "-1"], "values"),
        (
            vec!["sweep", "--model", model, "--input", "damper_c1", "--values", "1", "--return-period", "0.5"],
            "return_period",
        ),
    ] {
        let out = run(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(expected) && !stderr.contains("panicked"), "{args:?}: {stderr}");
    }
    std::fs::remove_dir_all(&dir).ok();
}
