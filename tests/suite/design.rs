//! The checks a design office signs and the sweeps that size its dampers, on the shared fixture:
//! a serviceability criterion that asks what an annual curve asks answers the curve's level
//! exactly, a sweep holds its input while the storms stay the same, and both routes answer the
//! library's numbers and refuse bad input naming the field.

use crate::harness::app::{assert_problem, database, problem_details, spawn_app};
use crate::harness::fixture;
use serde_json::{Value, json};
use windmeta::analysis::{
    Criterion, DEFAULT_RETURN_PERIODS, HazardOptions, OnThisMachine, Response, ResponseKind, Sampling,
    ServiceabilityOptions, Statistic, SweepOptions, Verdict, metamodel_hazard, metamodel_serviceability,
    metamodel_sweep,
};
use windmeta::progress::Silent;
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

/// One criterion at the roof's 10-year level aims the strata where an annual curve asking for the
/// 10-year level aims them (Neyman's scores doubled are the same allocation), so it draws the same
/// storms and must find the same level and band, to rounding; limits on either side of the band
/// give `pass` and `fail`.
#[test]
fn a_criterion_finds_the_annual_curves_level() {
    let (metamodel, study) = fixture::metamodel();
    let (samples, seed) = (400, 5);
    let hazard = HazardOptions {
        climate: CLIMATE,
        samples,
        seed,
        thresholds: None,
        return_periods: vec![10.0],
        limit: None,
        confidence: 0.95,
        sampling: Sampling::Stratified,
        certify: None,
    };
    let roof = Response::Acceleration { floor: 40 };
    let curve = metamodel_hazard(metamodel, study, roof, &hazard, &OnThisMachine, &Silent).unwrap();
    let level = &curve.return_levels[0];
    let (value, lower, upper) = (level.value.unwrap(), level.lower.unwrap(), level.upper.unwrap());
    let check = |limit: f64| {
        let options = ServiceabilityOptions {
            climate: CLIMATE,
            criteria: vec![roof_acceleration(limit)],
            samples,
            seed,
            confidence: 0.95,
        };
        metamodel_serviceability(metamodel, study, &options, &Silent).unwrap().criteria.remove(0)
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
    };
    let here = tokio::task::block_in_place(|| metamodel_serviceability(metamodel, study, &options, &Silent).unwrap());
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
    let here = tokio::task::block_in_place(|| metamodel_sweep(metamodel, study, roof, &options, &Silent).unwrap());
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
