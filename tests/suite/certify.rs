//! Certified curves on the shared fixture: the reference storms pair with the storms the metamodel
//! itself would draw, the certified curve agrees with plain reference Monte Carlo within its band,
//! and over HTTP a certified exceedance, fragility or annual request is an operation whose answer
//! carries the correction, its bad input refused naming the field.

use crate::harness::app::{TestApp, assert_problem, database, problem_details, spawn_app};
use crate::harness::fixture;
use serde_json::{Value, json};
use std::time::Duration;
use windmeta::analysis::{
    CertifyOptions, Draws, OnDivergence, OnThisMachine, Response, certify_exceedance, metamodel_peaks, paired_peaks,
    peaks_at, reference_storm_seed,
};
use windmeta::progress::Silent;
use windmeta::study::Order;
use windmeta::uncertainty::{monte_carlo, rng_from_seed};

/// The estimator is unbiased only if the paired storms' metamodel peaks are what the metamodel's
/// own sampling gives for the same inputs and winds: the scalar free run on the reference's forces
/// against the batched one on its own, storm by storm.
#[test]
fn reference_storms_pair_with_the_metamodels_own_storms() {
    let (metamodel, study) = fixture::metamodel();
    let roof = Response::Displacement { floor: study.structure.floors() };
    let seed = reference_storm_seed(3);
    let paired = paired_peaks(metamodel, study, &study.inputs, 24, seed, roof, Order::Reduced, &Silent).unwrap();
    let rows = monte_carlo(&study.inputs, 24, &mut rng_from_seed(seed));
    let storms: Vec<usize> = (0..24).collect();
    let draws = Draws { study, rows: &rows, storms: &storms, seed, on_divergence: OnDivergence::Fail };
    let batched = peaks_at(metamodel, &draws, roof, &OnThisMachine, &Silent).unwrap();
    for (pair, batched) in paired.iter().zip(&batched) {
        assert!((pair.metamodel - batched).abs() <= 1e-9 * batched, "{pair:?} against {batched}");
        // And the two models see the same storm (the fixture's peak error is about 0.3 %).
        assert!((pair.metamodel / pair.reference - 1.0).abs() < 0.05, "{pair:?}");
    }
    // Full order: the metamodel runs on the floor field's projection on the modes, the reference
    // on every floor; the modal cut and the metamodel's error together stay within 5 %.
    let full = paired_peaks(metamodel, study, &study.inputs, 4, seed, roof, Order::Full, &Silent).unwrap();
    for pair in &full {
        assert!((pair.metamodel / pair.reference - 1.0).abs() < 0.05, "full order: {pair:?}");
    }
}

/// The certified curve (600 metamodel storms, 120 through both models) against 600 other storms
/// through the reference alone: at every threshold the two differ by less than 2.5 standard
/// errors of their difference (the certified band's and the binomial one's, independent draws).
#[test]
fn the_certified_curve_agrees_with_reference_monte_carlo() {
    let (metamodel, study) = fixture::metamodel();
    let acceleration = Response::Acceleration { floor: study.structure.floors() };
    let (samples, seed) = (600, 8);
    let rows = monte_carlo(&study.inputs, samples, &mut rng_from_seed(seed));
    let storms: Vec<usize> = (0..samples).collect();
    let draws = Draws { study, rows: &rows, storms: &storms, seed, on_divergence: OnDivergence::Fail };
    let peaks = peaks_at(metamodel, &draws, acceleration, &OnThisMachine, &Silent).unwrap();
    let mut sorted = peaks.clone();
    sorted.sort_by(f64::total_cmp);
    let thresholds: Vec<f64> = [0.2, 0.5, 0.8].iter().map(|q| sorted[(q * samples as f64) as usize]).collect();
    let options = CertifyOptions { reference_storms: 120, order: Order::Reduced };
    let (curve, certification) = certify_exceedance(
        metamodel,
        study,
        &study.inputs,
        &peaks,
        &thresholds,
        Some(&options),
        seed,
        acceleration,
        0.95,
        &OnThisMachine,
        &Silent,
    )
    .unwrap();
    let certification = certification.expect("certified");
    assert_eq!(certification.reference_storms, 120);
    let reference = paired_peaks(metamodel, study, &study.inputs, samples, 99, acceleration, Order::Reduced, &Silent);
    let reference: Vec<f64> = reference.unwrap().iter().map(|p| p.reference).collect();
    for (i, &t) in thresholds.iter().enumerate() {
        let p_ref = reference.iter().filter(|&&r| r > t).count() as f64 / samples as f64;
        let certified_se = (curve.upper[i] - curve.lower[i]) / (2.0 * 1.96);
        let reference_se = (p_ref * (1.0 - p_ref) / samples as f64).sqrt();
        let gap = (curve.probabilities[i] - p_ref).abs();
        assert!(
            gap < 2.5 * certified_se.hypot(reference_se),
            "threshold {t}: certified {} [{}, {}], reference {p_ref}",
            curve.probabilities[i],
            curve.lower[i],
            curve.upper[i]
        );
        let correction = certification.correction[i];
        assert!(certification.correction_lower[i] <= correction && correction <= certification.correction_upper[i]);
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_certified_request_is_an_operation_with_its_correction() {
    let app = spawn_app(&database("certify")).await;
    let id = fixture::install(&app, fixture::STORM_S).await;
    let path = format!("/v1/metamodels/{id}/exceedance");
    // Small enough to be answered at once, but certified: queued all the same.
    let body = json!({"samples": 200, "seed": 2, "response": "acceleration", "certify": {"reference_storms": 40}});
    let (status, queued) = app.post_json(&path, body).await;
    assert_eq!(status, 202, "{queued}");
    let done = app.wait_for(queued["id"].as_str().unwrap(), &["succeeded", "failed"], Duration::from_secs(120)).await;
    assert_eq!(done["state"], "succeeded", "{done}");
    let result = &done["result"];
    let certification = &result["certification"];
    assert_eq!(certification["reference_storms"], 40);
    assert_eq!(certification["order"], "reduced");
    let count = result["thresholds"].as_array().unwrap().len();
    for key in [
        "metamodel_probabilities",
        "metamodel_lower",
        "metamodel_upper",
        "mismatch_rate",
        "correction",
        "correction_lower",
        "correction_upper",
    ] {
        assert_eq!(certification[key].as_array().map(Vec::len), Some(count), "{key}");
    }
    let number = |v: &Value| v.as_f64().unwrap();
    for i in 0..count {
        let p = number(&result["probabilities"][i]);
        let expected = number(&certification["metamodel_probabilities"][i]) + number(&certification["correction"][i]);
        assert!((p - expected.clamp(0.0, 1.0)).abs() < 1e-12, "threshold {i}");
        assert!(number(&result["lower"][i]) <= p && p <= number(&result["upper"][i]), "threshold {i}");
    }
    // Its reference storms ran as tasks (four of ten): the answer is the one this process computes.
    let (metamodel, study) = fixture::metamodel();
    let acceleration = Response::Acceleration { floor: study.structure.floors() };
    let here = tokio::task::block_in_place(|| {
        let peaks =
            metamodel_peaks(metamodel, study, &study.inputs, 200, 2, acceleration, &OnThisMachine, &Silent).unwrap();
        let thresholds: Vec<f64> = result["thresholds"].as_array().unwrap().iter().map(number).collect();
        let certify = CertifyOptions { reference_storms: 40, order: Order::Reduced };
        let inputs = &study.inputs;
        let (curve, certification) = certify_exceedance(
            metamodel,
            study,
            inputs,
            &peaks,
            &thresholds,
            Some(&certify),
            2,
            acceleration,
            0.95,
            &OnThisMachine,
            &Silent,
        )
        .unwrap();
        (curve, certification.unwrap())
    });
    let served: Vec<f64> = result["probabilities"].as_array().unwrap().iter().map(number).collect();
    let mismatches: Vec<f64> = certification["mismatch_rate"].as_array().unwrap().iter().map(number).collect();
    assert_eq!((served, mismatches), (here.0.probabilities, here.1.mismatch_rate));
    // Refused before anything is queued, naming the field.
    for (wrong, field) in [
        (json!({"samples": 100, "certify": {"reference_storms": 101}}), "certify.reference_storms"),
        (json!({"samples": 100, "certify": {"reference_storms": 0}}), "certify.reference_storms"),
        // Beyond the server's --max-reference-storms (1 000 by default).
        (json!({"samples": 2000, "certify": {"reference_storms": 1500}}), "certify.reference_storms"),
        (json!({"samples": 100, "certify": {"reference_storms": 10, "order": "sideways"}}), "certify"),
        (json!({"samples": 100, "certify": {"reference_storms": -3}}), "certify"),
    ] {
        let (s, ct, body) = problem_details(app.post(&path, wrong.clone()).await).await;
        assert_problem(s, &ct, &body, 422, field);
    }
    // Fragility, certified at each speed with the same reference draws: an operation whose
    // curves carry the correction per speed; more reference storms over every speed than the
    // server allows are refused.
    let fragility = format!("/v1/metamodels/{id}/fragility");
    let body = json!({"wind_speeds": [30, 36], "thresholds": [0.4], "samples": 60, "seed": 3,
                      "certify": {"reference_storms": 12}});
    let (status, queued) = app.post_json(&fragility, body).await;
    assert_eq!(status, 202, "{queued}");
    let done = app.wait_for(queued["id"].as_str().unwrap(), &["succeeded", "failed"], Duration::from_secs(120)).await;
    assert_eq!(done["state"], "succeeded", "{done}");
    let curve = &done["result"]["curves"][0];
    assert_eq!(curve["certification"]["reference_storms"], 12);
    assert_eq!(curve["certification"]["mismatch_rate"].as_array().map(Vec::len), Some(2), "{curve}");
    let too_many = json!({"wind_speeds": [30, 36], "thresholds": [0.4], "samples": 600,
                          "certify": {"reference_storms": 600}});
    let (s, ct, body) = problem_details(app.post(&fragility, too_many).await).await;
    assert_problem(s, &ct, &body, 422, "certify.reference_storms");
    certified_hazard(&app, &id).await;
    app.stop().await;
}

/// An annual curve certified with reference storms shared out over the wind strata: an
/// operation whose probabilities are the metamodel's plus the correction, whose storms per
/// stratum add up to those asked for at most, and whose return levels come from the certified
/// curve; too few reference storms for the strata are refused naming the field.
async fn certified_hazard(app: &TestApp, id: &str) {
    let hazard = format!("/v1/metamodels/{id}/hazard");
    let body = json!({"samples": 400, "seed": 4, "return_periods": [10, 100], "response": "acceleration",
                      "limit": 0.5, "certify": {"reference_storms": 48}});
    let (status, queued) = app.post_json(&hazard, body).await;
    assert_eq!(status, 202, "{queued}");
    let done = app.wait_for(queued["id"].as_str().unwrap(), &["succeeded", "failed"], Duration::from_secs(120)).await;
    assert_eq!(done["state"], "succeeded", "{done}");
    let curve = &done["result"];
    let certification = &curve["certification"];
    let per_stratum: Vec<u64> =
        certification["reference_storms_per_stratum"].as_array().unwrap().iter().map(|n| n.as_u64().unwrap()).collect();
    assert_eq!(per_stratum.len() as u64, curve["strata"].as_u64().unwrap());
    assert_eq!(per_stratum.iter().sum::<u64>(), certification["reference_storms"].as_u64().unwrap());
    assert!(per_stratum.iter().sum::<u64>() <= 48 && per_stratum.iter().all(|&n| n >= 3), "{per_stratum:?}");
    let number = |v: &Value| v.as_f64().unwrap();
    let count = curve["thresholds"].as_array().unwrap().len();
    for key in ["metamodel_probabilities", "mismatch_rate", "correction", "uncorrected_bound"] {
        assert_eq!(certification[key].as_array().map(Vec::len), Some(count), "{key}");
    }
    // The correction applies to the sampled part; the climate's unsampled tail is added after,
    // so a correction that takes the sampled part below zero leaves that tail.
    let unsampled = number(&curve["unsampled_probability"]);
    for i in 0..count {
        let p = number(&curve["annual_probability"][i]);
        let sampled = number(&certification["metamodel_probabilities"][i]) - unsampled;
        let expected = ((sampled + number(&certification["correction"][i])).clamp(0.0, 1.0) + unsampled).min(1.0);
        assert!((p - expected).abs() < 1e-12, "threshold {i}: {p} against {expected}");
        assert!(number(&curve["lower"][i]) <= p && p <= number(&curve["upper"][i]), "threshold {i}");
    }
    assert_eq!(curve["return_levels"].as_array().map(Vec::len), Some(2));
    assert!(curve["reliability"]["annual_probability"].is_number(), "{curve}");
    let too_few = json!({"samples": 400, "return_periods": [10, 100], "certify": {"reference_storms": 10}});
    let (s, ct, body) = problem_details(app.post(&hazard, too_few).await).await;
    assert_problem(s, &ct, &body, 422, "certify.reference_storms");
}

/// A certified request's reference storms report their own progress, and a cancellation stops them
/// within seconds (their tasks are withdrawn from every worker).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_certified_request_reports_its_reference_storms_and_stops_when_cancelled() {
    let app = spawn_app(&database("certify-cancel")).await;
    // Full-length storms: 400 reference storms would take most of a minute on two cores.
    let id = fixture::install(&app, 900.0).await;
    let body = json!({"samples": 1000, "response": "acceleration", "certify": {"reference_storms": 400}});
    let (status, queued) = app.post_json(&format!("/v1/metamodels/{id}/exceedance"), body).await;
    assert_eq!(status, 202, "{queued}");
    let op = queued["id"].as_str().unwrap();
    let started = std::time::Instant::now();
    loop {
        let (_, now) = app.get(&format!("/v1/operations/{op}")).await;
        let progress = &now["progress"];
        if progress["stage"] == "reference_storms" && progress["done"].as_u64().unwrap() > 0 {
            assert_eq!(progress["total"], 400, "{now}");
            break;
        }
        assert!(started.elapsed() < Duration::from_secs(60), "no reference storm reported: {now}");
        tokio::time::sleep(Duration::from_millis(200)).await;
    }
    let asked = std::time::Instant::now();
    let response = app.post(&format!("/v1/operations/{op}/cancel"), json!({})).await;
    assert_eq!(response.status().as_u16(), 200);
    let done = app.wait_for(op, &["cancelled", "failed", "succeeded"], Duration::from_secs(30)).await;
    assert_eq!(done["state"], "cancelled", "{done}");
    // A task stops within a second of its next heartbeat; well before the storms left would end.
    assert!(asked.elapsed() < Duration::from_secs(10), "cancelled after {:?}", asked.elapsed());
    app.stop().await;
}
