//! The service over real HTTP: a server on port 0 against a real SQLite file. The whole flow at
//! small size, bad input as problem+json, cancellation, and a restart in the middle of a job.

use crate::harness::app::{
    TestApp, assert_problem, database, problem_details, spawn_app, spawn_app_configured, spawn_app_with,
};
use crate::harness::fixture;
use crate::harness::postgres::fresh_postgres;
use crate::harness::proxy::Proxy;
use serde_json::{Value, json};
use std::time::{Duration, Instant};
use windmeta::progress::Silent;
use windmeta::study::{Study, StudySpec};
use windmeta::surrogate::{CalibrationOptions, calibrate};

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn calibrate_follow_fetch_and_sample() {
    let app = spawn_app(&database("flow")).await;
    assert_eq!(app.get("/healthz").await.0, 200);
    assert_eq!(app.get("/readyz").await.0, 200);
    let (status, presets) = app.get("/v1/presets").await;
    assert_eq!(status, 200);
    assert_eq!(presets["presets"].as_array().unwrap().len(), 2);
    assert_eq!(app.get("/v1/presets/frame40").await.1["floors"], 40);
    let defaults: Vec<&Value> =
        presets["presets"].as_array().unwrap().iter().filter(|p| p["default"] == true).collect();
    assert_eq!(defaults.len(), 1, "one preset is the default: {presets}");
    assert_eq!(defaults[0]["name"], "frame40-kn");

    let response = app
        .post("/v1/calibrations", json!({"preset": "frame40-kn", "experiments": 32, "duration_s": 30, "seed": 3}))
        .await;
    assert_eq!(response.status().as_u16(), 202);
    let location = response.headers()["location"].to_str().unwrap().to_string();
    let op: Value = response.json().await.unwrap();
    assert_eq!(location, format!("/v1/operations/{}", op["id"].as_str().unwrap()));
    // The same operation as server-sent events, to the end.
    let events = app.client.get(format!("{}{location}/events", app.address)).send().await.unwrap();
    assert_eq!(events.headers()["content-type"], "text/event-stream");
    let stream = tokio::time::timeout(Duration::from_secs(120), events.text()).await.expect("the stream ends").unwrap();
    assert!(stream.contains("event: operation") && stream.contains("\"state\":\"succeeded\""), "{stream}");
    let done = app.wait_for(op["id"].as_str().unwrap(), &["succeeded", "failed"], Duration::from_secs(120)).await;
    assert_eq!(done["state"], "succeeded", "{done}");
    let id = done["metamodel_id"].as_str().unwrap().to_string();

    let (status, metamodel) = app.get(&format!("/v1/metamodels/{id}")).await;
    assert_eq!(status, 200);
    assert_eq!(metamodel["format"], "windmeta-pc-narx");
    assert_eq!(metamodel["models"].as_array().unwrap().len(), 3);
    // The experiments beyond the 20 selection ones ran as tasks; the metamodel is bit for bit the
    // one the same calibration gives in one process.
    let spec = StudySpec { preset: Some("frame40-kn".into()), duration_s: Some(30.0), ..StudySpec::default() };
    let options = CalibrationOptions { experiments: 32, seed: 3, ..CalibrationOptions::default() };
    let local = calibrate(&Study::from_spec(&spec).unwrap(), &options, &Silent).unwrap();
    assert_eq!(metamodel["models"], serde_json::to_value(&local.models).unwrap());
    assert_eq!(app.get("/v1/metamodels").await.1["metamodels"][0]["id"], id.as_str());

    // Its study: the building, the storms, each input's law and the range its experiments spanned.
    let (status, study) = app.get(&format!("/v1/metamodels/{id}/study")).await;
    assert_eq!(status, 200);
    assert_eq!((study["floors"].as_u64(), study["damper_groups"].as_u64()), (Some(40), Some(4)), "{study}");
    assert_eq!((study["duration_s"].as_f64(), study["time_step_s"].as_f64()), (Some(30.0), Some(0.01)));
    assert_eq!(study["responses"].as_array().unwrap().len(), 6);
    let studied = Study::from_spec(&spec).unwrap();
    let design = windmeta::surrogate::design(&studied, &options).unwrap().points;
    let inputs = study["inputs"].as_array().unwrap();
    assert_eq!(inputs.len(), studied.inputs.inputs.len());
    for (k, input) in inputs.iter().enumerate() {
        assert_eq!(input["name"], studied.inputs.inputs[k].name.as_str());
        let values = design.iter().map(|x| x[k]);
        let range = [values.clone().fold(f64::INFINITY, f64::min), values.fold(f64::NEG_INFINITY, f64::max)];
        assert_eq!(input["calibrated_range"], json!(range), "{input}");
    }
    assert_eq!(inputs.last().unwrap()["marginal"]["distribution"], "frechet");
    assert_eq!(app.get("/v1/metamodels/nothing/study").await.0, 404);

    let path = format!("/v1/metamodels/{id}/exceedance");
    let curve: Value =
        app.post(&path, json!({"samples": 30, "seed": 2, "fixed": {"wind_speed": 32}})).await.json().await.unwrap();
    for key in ["thresholds", "probabilities", "lower", "upper"] {
        assert!(curve[key].as_array().is_some_and(|a| !a.is_empty()), "{key}: {curve}");
    }
    assert_eq!(curve["samples"], 30);
    let csv = app
        .client
        .post(format!("{}{path}", app.address))
        .header("accept", "text/csv")
        .json(&json!({"samples": 10}))
        .send()
        .await
        .unwrap();
    assert_eq!(csv.headers()["content-type"], "text/csv");
    assert!(csv.text().await.unwrap().starts_with("threshold_m,probability,lower,upper"));
    let svg = app
        .client
        .post(format!("{}{path}", app.address))
        .header("accept", "image/svg+xml")
        .json(&json!({"samples": 10}))
        .send()
        .await
        .unwrap();
    assert!(svg.text().await.unwrap().starts_with("<svg"));
    // The responses from the equations of motion, and a damper response where there is no damper.
    for response in ["acceleration", "damper_force", "damper_stroke"] {
        let (status, other) = app.post_json(&path, json!({"samples": 8, "response": response, "floor": 32})).await;
        assert_eq!(status, 200, "{response}: {other}");
        assert_eq!(other["response"]["kind"], response);
        assert!(other["thresholds"].as_array().unwrap().iter().all(|x| x.as_f64().unwrap() > 0.0), "{other}");
    }
    // Thresholds are in the response's unit: newtons for a damper force.
    let forces = json!({"samples": 8, "response": "damper_force", "floor": 32, "thresholds": [1000, 5000, 20000]});
    let (status, in_newtons) = app.post_json(&path, forces).await;
    assert_eq!((status, in_newtons["thresholds"].as_array().map(Vec::len)), (200, Some(3)), "{in_newtons}");
    let (s, ct, body) =
        problem_details(app.post(&path, json!({"samples": 8, "response": "damper_force", "floor": 99})).await).await;
    assert_problem(s, &ct, &body, 422, "floor");
    // A damper group's envelope: the largest of its dampers', at least the one below floor 32
    // (group 4), on the same storms.
    let group = json!({"samples": 8, "response": "damper_force", "group": 4, "thresholds": [1000, 5000, 20000]});
    let (status, envelope) = app.post_json(&path, group).await;
    assert_eq!(status, 200, "{envelope}");
    assert_eq!(envelope["response"], json!({"kind": "damper_force", "group": 4}));
    let exceeds = |answer: &Value| -> Vec<f64> {
        answer["probabilities"].as_array().unwrap().iter().map(|p| p.as_f64().unwrap()).collect()
    };
    assert!(exceeds(&envelope).iter().zip(exceeds(&in_newtons)).all(|(g, one)| *g >= one), "{envelope}");
    for (wrong, field) in [
        (json!({"samples": 8, "response": "drift", "group": 1}), "group"),
        (json!({"samples": 8, "response": "damper_force", "group": 1, "floor": 3}), "group"),
        (json!({"samples": 8, "response": "damper_force", "group": 9}), "group"),
    ] {
        let (s, ct, body) = problem_details(app.post(&path, wrong).await).await;
        assert_problem(s, &ct, &body, 422, field);
    }
    // The profile of the 90 % peak drift up the height, from the same storms as the curve: the
    // curve is the one without a profile, and each floor's band holds its quantile.
    let plain = json!({"samples": 60, "seed": 3, "response": "drift", "floor": 20});
    let (status, without) = app.post_json(&path, plain.clone()).await;
    assert_eq!(status, 200, "{without}");
    let mut profiled = plain.clone();
    profiled["profile_quantile"] = json!(0.9);
    let (status, with) = app.post_json(&path, profiled).await;
    assert_eq!(status, 200, "{with}");
    assert_eq!(with["probabilities"], without["probabilities"]);
    let profile = &with["profile"];
    let floors = profile["floors"].as_array().unwrap().len();
    assert_eq!((profile["response"].as_str(), profile["samples"].as_u64()), (Some("drift"), Some(60)), "{profile}");
    assert!(floors >= 20 && without.get("profile").is_none(), "{with}");
    for i in 0..floors {
        let at = |key: &str| profile[key][i].as_f64().unwrap();
        assert!(at("lower") <= at("values") && at("values") <= at("upper") && at("values") > 0.0, "{profile}");
    }
    let (s, ct, body) = problem_details(app.post(&path, json!({"samples": 8, "profile_quantile": 1.5})).await).await;
    assert_problem(s, &ct, &body, 422, "profile_quantile");
    let (s, ct, body) = problem_details(app.post(&path, json!({"samples": 8, "profile_quantile": 0.99})).await).await;
    assert_problem(s, &ct, &body, 422, "samples");
    // A CSV names the threshold's unit.
    let csv = app
        .client
        .post(format!("{}{path}", app.address))
        .header("accept", "text/csv")
        .json(&json!({"samples": 8, "response": "acceleration"}))
        .send()
        .await
        .unwrap();
    assert!(csv.text().await.unwrap().starts_with("threshold_m_s2,probability,lower,upper"));
    // The same request as an operation (what larger requests become).
    let queued = app
        .client
        .post(format!("{}{path}", app.address))
        .header("prefer", "respond-async")
        .json(&json!({"samples": 30, "seed": 2, "fixed": {"wind_speed": 32}}))
        .send()
        .await
        .unwrap();
    assert_eq!(queued.status().as_u16(), 202);
    let queued: Value = queued.json().await.unwrap();
    let done = app.wait_for(queued["id"].as_str().unwrap(), &["succeeded", "failed"], Duration::from_secs(60)).await;
    assert_eq!(done["kind"], "exceedance");
    assert_eq!(done["result"]["probabilities"], curve["probabilities"], "the operation's curve is the same");
    // What the study refuses is refused before anything is queued: a held input outside its
    // support, an unknown input, a floor the structure does not have.
    for (wrong, field) in [
        (json!({"samples": 30, "fixed": {"damping_ratio": -1}}), "fixed.damping_ratio"),
        (json!({"samples": 30, "fixed": {"colour": 3}}), "fixed.colour"),
        (json!({"samples": 30, "response": "drift", "floor": 99}), "floor"),
    ] {
        let asked = app.client.post(format!("{}{path}", app.address)).header("prefer", "respond-async").json(&wrong);
        let (s, ct, body) = problem_details(asked.send().await.unwrap()).await;
        assert_problem(s, &ct, &body, 422, field);
    }

    // The annual curve under a Gumbel climate through two return-period speeds, its CSV (one row
    // per threshold, the same numbers), its figure, and the same request as an operation.
    let hazard = format!("/v1/metamodels/{id}/hazard");
    // (A narrow climate: this small metamodel's design spans about 24 to 40 m/s, and its expansions
    // are not to be trusted far beyond.)
    let mut body = json!({"samples": 120, "seed": 4, "climate": {"return_period_speeds": {"50": 31, "700": 33}},
                          "return_periods": [10, 100]});
    let (status, annual) = app.post_json(&hazard, body.clone()).await;
    assert_eq!(status, 200, "{annual}");
    // A limit inside the curve: its probability and β = −Φ⁻¹(P).
    body["limit"] = annual["thresholds"][25].clone();
    let (status, annual) = app.post_json(&hazard, body.clone()).await;
    assert_eq!(status, 200, "{annual}");
    for key in [
        "thresholds",
        "annual_probability",
        "lower",
        "upper",
        "cov",
        "mri_years",
        "probability_beyond_calibrated_range",
    ] {
        assert_eq!(annual[key].as_array().map(Vec::len), Some(50), "{key}: {annual}");
    }
    assert_eq!(annual["climate"]["distribution"], "gumbel");
    assert_eq!(annual["return_levels"].as_array().unwrap().len(), 2);
    let beta = annual["reliability"]["beta"].as_f64().unwrap();
    assert!(beta.is_finite(), "{annual}");
    let csv = app.client.post(format!("{}{hazard}", app.address)).header("accept", "text/csv").json(&body).send();
    let csv = csv.await.unwrap().text().await.unwrap();
    let rows: Vec<&str> = csv.lines().skip(1).collect();
    assert_eq!(rows.len(), 50);
    let first: f64 = rows[0].split(',').nth(1).unwrap().parse().unwrap();
    assert_eq!(first, annual["annual_probability"][0].as_f64().unwrap());
    let svg = app.client.post(format!("{}{hazard}", app.address)).header("accept", "image/svg+xml").json(&body).send();
    assert!(svg.await.unwrap().text().await.unwrap().starts_with("<svg"));
    let queued = app.client.post(format!("{}{hazard}", app.address)).header("prefer", "respond-async").json(&body);
    let queued: Value = queued.send().await.unwrap().json().await.unwrap();
    let done = app.wait_for(queued["id"].as_str().unwrap(), &["succeeded", "failed"], Duration::from_secs(60)).await;
    assert_eq!(done["kind"], "hazard");
    assert_eq!(
        done["result"]["annual_probability"], annual["annual_probability"],
        "the operation's answer is the same"
    );
    // Checked before anything is queued, however large the request.
    let (s, ct, body) = problem_details(app.post(&hazard, json!({"floor": 0, "samples": 50000})).await).await;
    assert_problem(s, &ct, &body, 422, "floor");
    let (s, ct, body) = problem_details(app.post(&hazard, json!({"return_periods": [0.5]})).await).await;
    assert_problem(s, &ct, &body, 422, "return_periods");
    let (s, ct, body) = problem_details(
        app.post(&hazard, json!({"climate": {"distribution": "gumbel", "location": 100, "scale": 30}})).await,
    )
    .await;
    assert_problem(s, &ct, &body, 422, "climate");

    // Under the input model's own wind law the rarest strata reach speeds far beyond this small
    // metamodel's design, where some free runs diverge: they count as exceeding, and are counted.
    let (status, wide) = app.post_json(&hazard, json!({"samples": 120, "seed": 4})).await;
    assert_eq!(status, 200, "{wide}");
    let diverged = wide["diverged_storms"].as_u64().unwrap();
    assert!(diverged < 120, "{wide}");

    let (status, fragility) = app
        .post_json(
            &format!("/v1/metamodels/{id}/fragility"),
            json!({"wind_speeds": [28, 30, 32], "thresholds": [0.01, 0.02], "samples": 12, "seed": 2}),
        )
        .await;
    assert_eq!(status, 200, "{fragility}");
    assert_eq!(fragility["curves"].as_array().unwrap().len(), 2);
    assert_eq!(fragility["curves"][0]["probability"].as_array().unwrap().len(), 3);
    let (s, ct, body) =
        problem_details(app.post(&format!("/v1/metamodels/{id}/fragility"), json!({"samples": 10})).await).await;
    assert_problem(s, &ct, &body, 422, "thresholds");

    // A validation job against the reference on fresh samples.
    let response = app
        .post(
            &format!("/v1/metamodels/{id}/validations"),
            json!({"samples": 4, "seed": 9, "fixed": {"wind_speed": 38}}),
        )
        .await;
    assert_eq!(response.status().as_u16(), 202);
    let validation: Value = response.json().await.unwrap();
    let done =
        app.wait_for(validation["id"].as_str().unwrap(), &["succeeded", "failed"], Duration::from_secs(120)).await;
    assert_eq!(done["state"], "succeeded", "{done}");
    assert!(
        done["result"]["peak_correlation"].is_number() && done["result"]["mean_relative_error"].is_number(),
        "{done}"
    );
    assert_eq!(done["result"]["reference_peak"].as_array().unwrap().len(), 4);
    assert_eq!(done["result"]["fixed"], json!({"wind_speed": 38.0}));
    assert_eq!(done["metamodel_id"], id.as_str(), "a validation names the metamodel it validates");
    let (s, ct, body) =
        problem_details(app.post(&format!("/v1/metamodels/{id}/validations"), json!({"samples": 1})).await).await;
    assert_problem(s, &ct, &body, 422, "samples");
    let held = json!({"samples": 4, "fixed": {"damping_ratio": -1}});
    let (s, ct, body) = problem_details(app.post(&format!("/v1/metamodels/{id}/validations"), held).await).await;
    assert_problem(s, &ct, &body, 422, "fixed.damping_ratio");

    let metrics = app.client.get(format!("{}/metrics", app.address)).send().await.unwrap().text().await.unwrap();
    assert!(
        metrics.contains("windmeta_http_requests_total") && metrics.contains("route=\"/v1/operations/{id}\""),
        "{metrics}"
    );
    assert!(metrics.contains("windmeta_jobs_total"), "{metrics}");

    let deleted = app.client.delete(format!("{}/v1/metamodels/{id}", app.address)).send().await.unwrap();
    assert_eq!(deleted.status().as_u16(), 204);
    assert_eq!(app.get(&format!("/v1/metamodels/{id}")).await.0, 404);
    app.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn bad_input_is_refused_as_problem_json() {
    let app = spawn_app(&database("bad")).await;
    let raw = app
        .client
        .post(format!("{}/v1/calibrations", app.address))
        .header("content-type", "application/json")
        .body("{not json")
        .send()
        .await
        .unwrap();
    let (s, ct, body) = problem_details(raw).await;
    assert_problem(s, &ct, &body, 400, "");
    let (s, ct, body) = problem_details(app.post("/v1/calibrations", json!({"experiments": "many"})).await).await;
    assert_problem(s, &ct, &body, 422, "experiments");
    let (s, ct, body) = problem_details(app.post("/v1/calibrations", json!({"preset": "frame41"})).await).await;
    assert_problem(s, &ct, &body, 422, "preset");
    let (s, ct, body) = problem_details(app.post("/v1/calibrations", json!({"experiments": -5})).await).await;
    assert_problem(s, &ct, &body, 422, "experiments");
    let (s, ct, body) = problem_details(app.post("/v1/calibrations", json!({"experiments": 2})).await).await;
    assert_problem(s, &ct, &body, 422, "experiments");
    let (s, ct, body) = problem_details(app.post("/v1/calibrations", json!({"duration_s": 0})).await).await;
    assert_problem(s, &ct, &body, 422, "duration_s");
    let (s, ct, body) = problem_details(
        app.post("/v1/calibrations", json!({"inputs": {"stiffness": {"distribution": "constant", "value": 1}}})).await,
    )
    .await;
    assert_problem(s, &ct, &body, 422, "unknown input");
    let (s, ct, body) = problem_details(app.post("/v1/calibrations", json!({"surprise": 1})).await).await;
    assert_problem(s, &ct, &body, 422, "surprise");
    // Wind coverage: a range, or a climate, each checked and named; not both.
    let gumbel = json!({"distribution": "gumbel", "location": 25, "scale": 2.5});
    for (body, field) in [
        (json!({"cover_wind_speeds": {"lower": 40, "upper": 30}}), "cover_wind_speeds"),
        (json!({"cover_wind_speeds": {"lower": 30, "upper": 1e9}}), "cover_wind_speeds"),
        (json!({"cover_wind_speeds": {"lower": 30}}), "upper"),
        (json!({"cover_climate": {"climate": gumbel, "annual_probability": 0.9}}), "cover_climate.annual_probability"),
        (json!({"cover_climate": {"climate": {"distribution": "gumbel", "location": 25}}}), "scale"),
        (json!({"cover_climate": {"climate": gumbel}, "cover_wind_speeds": {"lower": 30, "upper": 60}}), "not both"),
        (
            json!({"inputs": {"wind_speed": {"distribution": "constant", "value": 30}},
                "cover_wind_speeds": {"lower": 30, "upper": 60}}),
            "holds wind_speed fixed",
        ),
    ] {
        let (s, ct, problem_body) = problem_details(app.post("/v1/calibrations", body.clone()).await).await;
        assert_problem(s, &ct, &problem_body, 422, field);
    }
    let huge = json!({"preset": "frame40", "structure": {"mass": vec![vec![1.0; 200]; 200]}});
    let (s, ct, body) = problem_details(app.post("/v1/calibrations", huge).await).await;
    assert_problem(s, &ct, &body, 413, "");
    let (s, ct, body) =
        problem_details(app.client.get(format!("{}/v1/operations/nope", app.address)).send().await.unwrap()).await;
    assert_problem(s, &ct, &body, 404, "nope");
    let (s, ct, body) = problem_details(app.post("/v1/metamodels/nope/exceedance", json!({"samples": 10})).await).await;
    assert_problem(s, &ct, &body, 404, "nope");
    let (s, ct, body) = problem_details(app.post("/v1/metamodels/nope/exceedance", json!({"samples": -1})).await).await;
    assert_problem(s, &ct, &body, 422, "samples");
    app.stop().await;
}

/// A retry under the same Idempotency-Key gets the same operation; another body under it is refused.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn idempotency_keys_replay_the_operation() {
    let app = spawn_app(&database("idempotency")).await;
    let url = format!("{}/v1/calibrations", app.address);
    let body = json!({"experiments": 4, "duration_s": 10});
    let send = |body: Value| app.client.post(&url).header("idempotency-key", "k-1").json(&body).send();
    let first = send(body.clone()).await.unwrap();
    assert_eq!(first.status().as_u16(), 202);
    let first_location = first.headers()["location"].clone();
    let again = send(body.clone()).await.unwrap();
    assert_eq!(again.status().as_u16(), 202);
    assert_eq!(again.headers()["location"], first_location);
    let (s, ct, problem_body) = problem_details(send(json!({"experiments": 5, "duration_s": 10})).await.unwrap()).await;
    assert_problem(s, &ct, &problem_body, 422, "Idempotency-Key");
    let (_, list) = app.get("/v1/operations").await;
    assert_eq!(list["operations"].as_array().unwrap().len(), 1);
    let other = app.client.post(&url).header("idempotency-key", "k-2").json(&body).send().await.unwrap();
    assert_ne!(other.headers()["location"], first_location);
    app.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn cancellation_stops_a_running_calibration() {
    let app = spawn_app(&database("cancel")).await;
    let op: Value = app.post("/v1/calibrations", json!({"experiments": 200})).await.json().await.unwrap();
    let id = op["id"].as_str().unwrap();
    app.wait_for(id, &["running"], Duration::from_secs(30)).await;
    let asked = Instant::now();
    let response = app.post(&format!("/v1/operations/{id}/cancel"), json!({})).await;
    assert_eq!(response.status().as_u16(), 200);
    let op = app.wait_for(id, &["cancelled", "failed", "succeeded"], Duration::from_secs(30)).await;
    assert_eq!(op["state"], "cancelled");
    eprintln!("cancelled {:.1} s after the request", asked.elapsed().as_secs_f64());
    app.stop().await;
}

/// A calibration long enough to be interrupted (24 experiments of 120 s), once it runs: its id.
async fn running_calibration(app: &TestApp) -> String {
    let op: Value = app
        .post("/v1/calibrations", json!({"experiments": 24, "duration_s": 120, "seed": 5}))
        .await
        .json()
        .await
        .unwrap();
    let id = op["id"].as_str().unwrap().to_string();
    app.wait_for(&id, &["running"], Duration::from_secs(30)).await;
    id
}

/// Stop the server in the middle of a calibration, start it again on the same file: the job is
/// taken up again and finishes; nothing stored is lost.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_restart_takes_the_job_up_again() {
    let db = database("restart");
    let first = spawn_app(&db).await;
    let id = running_calibration(&first).await;
    tokio::time::sleep(Duration::from_millis(500)).await;
    first.stop().await;
    let second = spawn_app(&db).await;
    let done = second.wait_for(&id, &["succeeded", "failed"], Duration::from_secs(180)).await;
    assert_eq!(done["state"], "succeeded", "{done}");
    assert!(done["attempts"].as_i64().unwrap() >= 2, "{done}");
    let metamodel = done["metamodel_id"].as_str().unwrap();
    assert_eq!(second.get(&format!("/v1/metamodels/{metamodel}")).await.0, 200);
    second.stop().await;
}

/// A database locked for longer than the lease leaves the worker unsure whether the job is still
/// its own: it stops and gives the job back to the queue, where it is taken up again. Only a client
/// may have a job recorded as cancelled.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_lease_in_doubt_gives_the_job_back_instead_of_cancelling_it() {
    use sqlx::Connection;
    let db = database("lease-in-doubt");
    let app = spawn_app(&db).await;
    let id = running_calibration(&app).await;
    // Longer than the lease (2 s) plus SQLite's busy timeout (5 s): a heartbeat fails after the
    // lease has run out.
    let mut lock = sqlx::SqliteConnection::connect(&format!("sqlite://{}", db.display())).await.unwrap();
    sqlx::raw_sql("BEGIN IMMEDIATE").execute(&mut lock).await.unwrap();
    tokio::time::sleep(Duration::from_secs(8)).await;
    sqlx::raw_sql("ROLLBACK").execute(&mut lock).await.unwrap();
    let done = app.wait_for(&id, &["succeeded", "failed", "cancelled"], Duration::from_secs(180)).await;
    assert_eq!(done["state"], "succeeded", "{done}");
    assert!(done["attempts"].as_i64().unwrap() >= 2, "{done}");
    app.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn api_keys_and_cors() {
    let app = spawn_app_with(&database("auth"), vec!["s3cret".into()], vec!["https://office.example".into()]).await;
    assert_eq!(app.get("/healthz").await.0, 200);
    let (s, ct, body) =
        problem_details(app.client.get(format!("{}/v1/presets", app.address)).send().await.unwrap()).await;
    assert_problem(s, &ct, &body, 401, "Bearer");
    let wrong = app.client.get(format!("{}/v1/presets", app.address)).bearer_auth("guess").send().await.unwrap();
    assert_eq!(wrong.status().as_u16(), 401);
    assert_eq!(wrong.headers()["www-authenticate"], "Bearer");
    let right = app.client.get(format!("{}/v1/presets", app.address)).bearer_auth("s3cret").send().await.unwrap();
    assert_eq!(right.status().as_u16(), 200);
    let preflight = app
        .client
        .request(reqwest::Method::OPTIONS, format!("{}/v1/calibrations", app.address))
        .header("origin", "https://office.example")
        .header("access-control-request-method", "POST")
        .send()
        .await
        .unwrap();
    assert_eq!(preflight.headers()["access-control-allow-origin"], "https://office.example");
    let other = app
        .client
        .get(format!("{}/healthz", app.address))
        .header("origin", "https://elsewhere.example")
        .send()
        .await
        .unwrap();
    assert!(other.headers().get("access-control-allow-origin").is_none());
    let exposed = app
        .client
        .get(format!("{}/healthz", app.address))
        .header("origin", "https://office.example")
        .send()
        .await
        .unwrap();
    assert!(exposed.headers()["access-control-expose-headers"].to_str().unwrap().contains("location"));
    app.stop().await;
}

/// The (method, path template, status) triples the API description documents.
fn documented_statuses(spec: &Value) -> Vec<(String, String, u16)> {
    let mut out = Vec::new();
    for (path, item) in spec["paths"].as_object().unwrap() {
        for (method, operation) in item.as_object().unwrap() {
            for status in operation["responses"].as_object().unwrap().keys() {
                out.push((method.to_uppercase(), path.clone(), status.parse().unwrap()));
            }
        }
    }
    out
}

/// The documented response, following a `$ref` to a shared one.
fn documented_response<'a>(spec: &'a Value, method: &str, path: &str, status: u16) -> &'a Value {
    let response = &spec["paths"][path][method.to_lowercase()]["responses"][status.to_string()];
    match response["$ref"].as_str() {
        Some(reference) => &spec["components"]["responses"][reference.rsplit('/').next().unwrap()],
        None => response,
    }
}

fn keys(value: &Value) -> Vec<String> {
    value.as_object().map(|o| o.keys().cloned().collect()).unwrap_or_default()
}

/// When the server has to be in a particular state for a status to be reachable.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Phase {
    Normal,
    QueueFull,
    /// The database answers with errors (its tables renamed away).
    DatabaseBroken,
    /// The database does not answer at all: provoked on PostgreSQL behind a proxy that is cut
    /// (`a_database_outage_is_answered_503`).
    DatabaseDown,
}

fn phase_of(spec: &Value, method: &str, path: &str, status: u16) -> Phase {
    let shared = spec["paths"][path][method.to_lowercase()]["responses"][status.to_string()]["$ref"].as_str();
    if shared == Some("#/components/responses/DatabaseUnavailable") {
        return Phase::DatabaseDown;
    }
    match status {
        500 => Phase::DatabaseBroken,
        503 if path == "/readyz" => Phase::DatabaseBroken,
        503 => Phase::QueueFull,
        _ => Phase::Normal,
    }
}

const KEY: &str = "contract-key";

struct Ids {
    metamodel: String,
    doomed_metamodel: String,
    operation: String,
}

/// Sends the request that should make `method path` answer `status`.
async fn provoke(app: &TestApp, ids: &Ids, method: &str, template: &str, status: u16) -> reqwest::Response {
    let id = match (template, status) {
        (_, 404) => "missing",
        (t, _) if t.starts_with("/v1/presets/") => "frame40",
        (t, 204) if t.starts_with("/v1/metamodels/") => &ids.doomed_metamodel,
        (t, _) if t.starts_with("/v1/metamodels/") => &ids.metamodel,
        _ => &ids.operation,
    };
    let path = template.replace("{id}", id).replace("{name}", id);
    let has_body = method == "POST" && !path.ends_with("/cancel");
    let valid_body = match template {
        "/v1/calibrations" => json!({"experiments": 4, "duration_s": 10}),
        "/v1/metamodels/{id}/exceedance" => json!({"samples": 10}),
        "/v1/metamodels/{id}/validations" => json!({"samples": 2}),
        "/v1/metamodels/{id}/hazard" => {
            json!({"samples": 60, "return_periods": [2], "climate": {"return_period_speeds": {"2": 29, "50": 31}}})
        }
        "/v1/metamodels/{id}/fragility" => json!({"thresholds": [0.01], "wind_speeds": [29, 31], "samples": 10}),
        "/v1/metamodels/{id}/sensitivity" => json!({"samples": 10, "seed": 2}),
        "/v1/metamodels/{id}/demands" => json!({"wind_speed": 40, "samples": 5}),
        "/v1/metamodels/{id}/serviceability" => json!({"criteria": ["nbcc-office"], "samples": 60}),
        "/v1/metamodels/{id}/sweep" => json!({"input": "damper_c4", "values": [0, 50000], "samples": 60}),
        _ => json!({}),
    };
    let invalid_body = match template {
        "/v1/calibrations" => json!({"experiments": 2}),
        "/v1/metamodels/{id}/exceedance" => json!({"samples": 0}),
        "/v1/metamodels/{id}/demands" => json!({"wind_speed": 40, "samples": 0}),
        _ => json!({"samples": 1}),
    };
    let url = |query: &str| format!("{}{path}{query}", app.address);
    let request = |query: &str| {
        app.client.request(reqwest::Method::from_bytes(method.as_bytes()).unwrap(), url(query)).bearer_auth(KEY)
    };
    let request = match status {
        401 => app.client.request(reqwest::Method::from_bytes(method.as_bytes()).unwrap(), url("")).json(&valid_body),
        400 if has_body => request("").header("content-type", "application/json").body("{not json"),
        400 => request("?limit=many"),
        413 => request("").json(&json!({"seed": 1, "padding": "x".repeat(70 * 1024)})),
        415 => request("").header("content-type", "text/plain").body(valid_body.to_string()),
        422 if has_body => request("").json(&invalid_body),
        422 => request("?limit=0"),
        202 | 500 | 503
            if ["/exceedance", "/hazard", "/fragility", "/sensitivity", "/serviceability", "/sweep"]
                .iter()
                .any(|e| template.ends_with(e)) =>
        {
            request("").header("prefer", "respond-async").json(&valid_body)
        }
        _ if has_body => request("").json(&valid_body),
        _ => request(""),
    };
    request.send().await.unwrap()
}

/// Checks an answer against the description: its status, the headers and the media type documented
/// for that status.
async fn assert_as_documented(spec: &Value, method: &str, path: &str, status: u16, response: reqwest::Response) {
    let documented_response = documented_response(spec, method, path, status);
    for header in keys(&documented_response["headers"]) {
        assert!(response.headers().contains_key(header.as_str()), "{method} {path} {status}: no {header}");
    }
    let got = response.status().as_u16();
    let media = response.headers().get("content-type").map(|v| v.to_str().unwrap().to_string());
    let body = response.text().await.unwrap_or_default();
    assert_eq!(got, status, "{method} {path} answered {got}, not the documented {status}: {body}");
    let documented_media = keys(&documented_response["content"]);
    match media {
        None => assert!(documented_media.is_empty(), "{method} {path} {status}: no content type"),
        Some(media) => assert!(
            documented_media.iter().any(|d| media.starts_with(d.as_str())),
            "{method} {path} {status}: `{media}` is not among {documented_media:?}"
        ),
    }
}

/// While PostgreSQL does not answer (the connection through a proxy cut: every open connection
/// reset, new ones refused), every route that reads or writes the database answers 503 with
/// `Retry-After`, as its description says, not 500; once it answers again, so do they.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_database_outage_is_answered_503() {
    let Some(url) = fresh_postgres().await else { return };
    let proxy = Proxy::start("127.0.0.1:5432").await;
    let proxied = url.replacen("127.0.0.1:5432", &format!("127.0.0.1:{}", proxy.port), 1);
    assert_ne!(proxied, url, "the test database is not at 127.0.0.1:5432: {url}");
    let app = spawn_app_configured(&database("outage"), |args| {
        args.database_url = proxied;
        args.api_keys = vec![KEY.into()];
    })
    .await;
    let (operation, metamodel) = calibrate_over_http(&app, json!({"experiments": 4, "duration_s": 10})).await;
    let ids = Ids { doomed_metamodel: metamodel.clone(), metamodel, operation: operation.clone() };
    let spec = serde_json::to_value(windmeta::service::openapi_for(&app.config)).unwrap();
    let down: Vec<_> = documented_statuses(&spec)
        .into_iter()
        .filter(|(m, p, s)| phase_of(&spec, m, p, *s) == Phase::DatabaseDown)
        .collect();
    for named in [("GET", "/v1/operations/{id}"), ("GET", "/v1/metamodels"), ("GET", "/v1/metamodels/{id}/study")] {
        assert!(down.iter().any(|(m, p, _)| (m.as_str(), p.as_str()) == named), "{named:?} not in {down:?}");
    }
    proxy.cut();
    for (method, path, status) in &down {
        let response = provoke(&app, &ids, method, path, *status).await;
        assert_as_documented(&spec, method, path, *status, response).await;
    }
    proxy.restore();
    let answer = app.client.get(format!("{}/v1/operations/{operation}", app.address)).bearer_auth(KEY).send().await;
    assert_eq!(answer.unwrap().status().as_u16(), 200, "the database answers again");
    app.stop().await;
}

/// Waits until no operation is queued or running, cancelling what is.
async fn drain_operations(app: &TestApp) {
    let list =
        |app: &TestApp| app.client.get(format!("{}/v1/operations?limit=500", app.address)).bearer_auth(KEY).send();
    for _ in 0..300 {
        let operations: Value = list(app).await.unwrap().json().await.unwrap();
        let open: Vec<String> = operations["operations"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|o| o["done"] == false)
            .map(|o| o["id"].as_str().unwrap().to_string())
            .collect();
        if open.is_empty() {
            return;
        }
        for id in open {
            let url = format!("{}/v1/operations/{id}/cancel", app.address);
            app.client.post(url).bearer_auth(KEY).send().await.unwrap();
        }
        tokio::time::sleep(Duration::from_millis(200)).await;
    }
    panic!("operations did not stop");
}

async fn calibrate_over_http(app: &TestApp, body: Value) -> (String, String) {
    let url = format!("{}/v1/calibrations", app.address);
    let op: Value = app.client.post(url).bearer_auth(KEY).json(&body).send().await.unwrap().json().await.unwrap();
    let id = op["id"].as_str().unwrap().to_string();
    let url = format!("{}/v1/operations/{id}", app.address);
    for _ in 0..600 {
        let op: Value = app.client.get(&url).bearer_auth(KEY).send().await.unwrap().json().await.unwrap();
        if op["done"] == true {
            assert_eq!(op["state"], "succeeded", "{op}");
            return (id, op["metamodel_id"].as_str().unwrap().to_string());
        }
        tokio::time::sleep(Duration::from_millis(200)).await;
    }
    panic!("the calibration did not finish");
}

/// Every status the API description documents for an operation is one the server really returns:
/// each is provoked over HTTP (with the server in the state that allows it: a full queue, a broken
/// database) and the answer's status and media type are checked against the description.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn every_documented_status_is_real() {
    let db = database("contract");
    let app = spawn_app_configured(&db, |args| {
        args.api_keys = vec![KEY.into()];
        args.max_queued_jobs = 1;
        args.max_event_streams = 1;
    })
    .await;
    let spec: Value =
        app.client.get(format!("{}/openapi.json", app.address)).send().await.unwrap().json().await.unwrap();
    let contract = windmeta::service::openapi_for(&app.config);
    assert_eq!(spec, serde_json::to_value(contract).unwrap(), "/openapi.json is the contract");
    assert_eq!(spec["components"]["schemas"]["ExceedanceRequest"]["properties"]["samples"]["maximum"], 2000.0);
    let (operation, _) = calibrate_over_http(&app, json!({"experiments": 4, "duration_s": 10})).await;
    let metamodel = fixture::install(&app, fixture::STORM_S).await;
    let doomed_metamodel = fixture::install(&app, fixture::STORM_S).await;
    let ids = Ids { metamodel, doomed_metamodel, operation };
    let documented = documented_statuses(&spec);
    eprintln!("provoking {} documented (operation, status) pairs", documented.len());
    // The event stream held open in the full phase, so that the only stream allowed is taken.
    let mut held_stream = None;
    for phase in [Phase::Normal, Phase::QueueFull, Phase::DatabaseBroken] {
        match phase {
            // Provoked by `a_database_outage_is_answered_503`.
            Phase::Normal | Phase::DatabaseDown => {}
            Phase::QueueFull => {
                drain_operations(&app).await;
                // One long calibration runs on the single worker, the next waits: the queue is full.
                let url = format!("{}/v1/calibrations", app.address);
                let mut full = false;
                let mut running = None;
                for _ in 0..20 {
                    let r = app.client.post(&url).bearer_auth(KEY).json(&json!({"experiments": 200})).send().await;
                    let r = r.unwrap();
                    full = r.status() == 503;
                    if full {
                        break;
                    }
                    let op: Value = r.json().await.unwrap();
                    running.get_or_insert(op["id"].as_str().unwrap().to_string());
                    tokio::time::sleep(Duration::from_millis(300)).await;
                }
                assert!(full, "the queue never filled");
                let events = format!("{}/v1/operations/{}/events", app.address, running.unwrap());
                let stream = app.client.get(events).bearer_auth(KEY).send().await.unwrap();
                assert_eq!(stream.status().as_u16(), 200);
                held_stream = Some(stream);
            }
            Phase::DatabaseBroken => {
                held_stream.take();
                drain_operations(&app).await;
                let pool = sqlx::SqlitePool::connect(&format!("sqlite://{}", db.display())).await.unwrap();
                for statement in
                    ["ALTER TABLE jobs RENAME TO jobs_moved", "ALTER TABLE metamodels RENAME TO metamodels_moved"]
                {
                    sqlx::query(statement).execute(&pool).await.unwrap();
                }
            }
        }
        let provoked = documented.iter().filter(|(m, p, s)| phase_of(&spec, m, p, *s) == phase);
        for (method, path, status) in provoked {
            if *status == 202 {
                drain_operations(&app).await; // the queue holds one job in this test
            }
            let response = provoke(&app, &ids, method, path, *status).await;
            assert_as_documented(&spec, method, path, *status, response).await;
        }
    }
    app.stop().await;
}
