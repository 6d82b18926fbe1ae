//! The commands as a user runs them: outputs, reproducibility, and refusals of bad input with a
//! message naming what is wrong and a non-zero exit.

use crate::harness::app::database;
use serde_json::Value;
use std::io::{BufRead, BufReader};
use std::process::{Command, Output, Stdio};

fn windmeta(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_windmeta")).args(args).output().expect("the binary runs")
}

fn json(args: &[&str]) -> Value {
    let out = windmeta(args);
    assert!(out.status.success(), "{args:?}: {}", String::from_utf8_lossy(&out.stderr));
    serde_json::from_slice(&out.stdout).expect("JSON on stdout")
}

fn refused(args: &[&str], expected: &str) {
    let out = windmeta(args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{args:?} should be refused as bad input; stderr: {stderr}");
    assert!(stderr.contains(expected), "{args:?}: expected `{expected}` in: {stderr}");
    assert!(!stderr.contains("panicked"), "{args:?} panicked: {stderr}");
}

#[test]
fn modes_reports_the_papers_frequencies() {
    let v = json(&["modes", "--preset", "frame40", "--json"]);
    let w: Vec<f64> = v["frequencies_rad_s"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
    assert_eq!(w.len(), 3);
    for (w, expected) in w.iter().zip([1.44, 4.09, 7.09]) {
        assert!((w / expected - 1.0).abs() < 0.01, "{w} vs {expected}");
    }
    let t = v["periods_s"][0].as_f64().unwrap();
    assert!((t * w[0] - 2.0 * std::f64::consts::PI).abs() < 1e-9);
    assert_eq!(v["shapes"][0].as_array().unwrap().len(), 40);
    assert_eq!(v["shapes"][2][39].as_f64().unwrap(), 1.0);
    assert!(v["modal_masses_kg"][0].as_f64().unwrap() > 1e6);
}

/// The three-dimensional preset: the plane frame's first mode in x and in y, then its twist at √3
/// times its frequency (the closed form of the symmetric building); with an eccentricity along y
/// the x-sway takes a share of twist; its studies are refused by name until they exist.
#[test]
fn modes_of_the_three_dimensional_preset_show_their_shares() {
    let plane = json(&["modes", "--preset", "frame40", "--json"]);
    let w1 = plane["frequencies_rad_s"][0].as_f64().unwrap();
    let v = json(&["modes", "--preset", "frame40-3d", "--json", "--modes", "3"]);
    let w: Vec<f64> = v["frequencies_rad_s"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
    for (w, expected) in w.iter().zip([w1, w1, 3f64.sqrt() * w1]) {
        assert!((w / expected - 1.0).abs() < 1e-9, "{w} vs {expected}");
    }
    for (m, kind) in ["x", "y", "rotation"].iter().enumerate() {
        assert!((v["shares"][m][kind].as_f64().unwrap() - 1.0).abs() < 1e-9, "mode {}: {}", m + 1, v["shares"][m]);
    }
    assert_eq!(v["shapes"][0]["x_m"].as_array().unwrap().len(), 40);
    let eccentric = json(&["modes", "--preset", "frame40-3d", "--json", "--fix", "eccentricity_y=2.44"]);
    let twist = eccentric["shares"][0]["rotation"].as_f64().unwrap();
    assert!(twist > 1e-3 && twist < 0.1, "the first mode's twist share {twist}");
    refused(&["modes", "--preset", "frame40-3d", "--fix", "eccentricity_y=9"], "inputs.eccentricity_y");
    refused(&["modes", "--preset", "frame40", "--fix", "eccentricity_y=1"], "eccentricity_y");
    refused(&["calibrate", "--preset", "frame40-3d", "--out", "/nonexistent/model.json"], "three-dimensional");
}

/// One storm from a direction on the three-dimensional preset: the square building turned by 90°
/// is itself, so wind towards y sways it along y as wind towards x sways it along x (the same
/// random phases); the corner's resultant acceleration is at least either sway's.
#[test]
fn simulate_runs_the_three_dimensional_preset_from_a_direction() {
    let run = |direction: &str, extra: &[&str]| {
        let fix = format!("wind_direction={direction}");
        let mut args = vec![
            "simulate",
            "--preset",
            "frame40-3d",
            "--duration",
            "60",
            "--fix",
            "wind_speed=35",
            "--fix",
            &fix,
            "--json",
        ];
        // Seven modes: x1, y1, θ1, x2, y2 and the pair x3, y3, a basis the 90° turn maps onto itself.
        args.extend_from_slice(&["--modes", "7"]);
        args.extend_from_slice(extra);
        json(&args)
    };
    let column = |v: &Value, name: &str| -> Vec<f64> {
        v["peaks"][name].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect()
    };
    let along_x = run("0", &[]);
    let along_y = run("90", &[]);
    let (x0, y0) = (column(&along_x, "displacement_x_m"), column(&along_x, "displacement_y_m"));
    let (x90, y90) = (column(&along_y, "displacement_x_m"), column(&along_y, "displacement_y_m"));
    assert_eq!(x0.len(), 40);
    for j in [19, 39] {
        assert!((y90[j] / x0[j] - 1.0).abs() < 1e-6, "floor {}: {} against {}", j + 1, y90[j], x0[j]);
        assert!((x90[j] / y0[j] - 1.0).abs() < 1e-6, "floor {}: {} against {}", j + 1, x90[j], y0[j]);
    }
    // The published model's across-wind load sways it across the wind too.
    assert!(y0[39] > 0.01 * x0[39], "across-wind sway {} against {}", y0[39], x0[39]);
    let corner = column(&along_x, "corner_acceleration_m_s2");
    let (ax, ay) = (column(&along_x, "acceleration_x_m_s2"), column(&along_x, "acceleration_y_m_s2"));
    assert!(corner[39] >= ax[39].max(ay[39]) * (1.0 - 1e-12), "{} against {} and {}", corner[39], ax[39], ay[39]);
    assert!(column(&along_x, "rms_corner_acceleration_m_s2")[39] < corner[39]);
    let tunnel = concat!(env!("CARGO_MANIFEST_DIR"), "/docs/data/wind-tunnel-example.json");
    let measured = run("30", &["--wind-tunnel", tunnel]);
    assert_eq!(measured["wake_loads"], "wind_tunnel");
    assert_eq!(measured["records_direction_deg"], Value::Null);
    assert!(column(&measured, "rotation_rad")[39] > 0.0);
    refused(
        &["simulate", "--preset", "frame40-3d", "--duration", "60", "--wind-tunnel", "/nonexistent.json"],
        "wind-tunnel",
    );
    refused(&["simulate", "--preset", "frame40-kn", "--wind-tunnel", tunnel], "wind-tunnel");
    refused(&["simulate", "--preset", "frame40-3d", "--fix", "wind_direction=NaN"], "wind_direction");

    // Histories: every direction of the roof's displacement and its worst corner's acceleration,
    // whose peaks are the run's.
    let dir = std::env::temp_dir().join(format!("windmeta-3d-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let csv = dir.join("histories.csv");
    let csv_arg = csv.to_str().unwrap();
    let written = run("30", &["--out", csv_arg, "--history", "displacement", "--history", "corner_acceleration"]);
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(
        header,
        [
            "t_s",
            "displacement_40_x_m",
            "displacement_40_y_m",
            "displacement_40_rotation_rad",
            "corner_acceleration_40_m_s2"
        ]
    );
    let mut largest = [0.0f64; 4];
    for line in lines {
        for (l, v) in largest.iter_mut().zip(line.split(',').skip(1)) {
            *l = l.max(v.parse::<f64>().unwrap().abs());
        }
    }
    for (l, name) in
        largest.iter().zip(["displacement_x_m", "displacement_y_m", "rotation_rad", "corner_acceleration_m_s2"])
    {
        let peak = column(&written, name)[39];
        assert!((l / peak - 1.0).abs() < 1e-8, "{name}: history's largest {l} against the peak {peak}");
    }
    refused(
        &["simulate", "--preset", "frame40-3d", "--out", csv_arg, "--history", "rms_corner_acceleration"],
        "history",
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// Peaks of a three-dimensional building over storms from random directions, by response and
/// direction; an uncertain eccentricity is an input like the others.
#[test]
fn sample_peaks_runs_the_three_dimensional_preset() {
    let base =
        ["sample-peaks", "--preset", "frame40-3d", "--samples", "2", "--duration", "30", "--modes", "6", "--json"];
    let peaks = |extra: &[&str]| -> Vec<f64> {
        let args: Vec<&str> = base.iter().chain(extra).copied().collect();
        let v = json(&args);
        v["peaks"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect()
    };
    let corner = peaks(&["--response", "corner_acceleration"]);
    let along_x = peaks(&["--response", "acceleration", "--direction", "x"]);
    let along_y = peaks(&["--response", "acceleration", "--direction", "y"]);
    assert_eq!(corner.len(), 2);
    for k in 0..2 {
        assert!(
            corner[k] >= along_x[k].max(along_y[k]) * (1.0 - 1e-12),
            "storm {k}: {corner:?} {along_x:?} {along_y:?}"
        );
    }
    let spec_dir = std::env::temp_dir().join(format!("windmeta-3d-spec-{}", std::process::id()));
    std::fs::create_dir_all(&spec_dir).unwrap();
    let spec = spec_dir.join("eccentric.json");
    std::fs::write(
        &spec,
        r#"{"preset": "frame40-3d", "inputs": {"eccentricity_y": {"distribution": "uniform", "lower": -1.2, "upper": 1.2}}}"#,
    )
    .unwrap();
    let v = json(&[
        "sample-peaks",
        "--spec",
        spec.to_str().unwrap(),
        "--samples",
        "2",
        "--duration",
        "30",
        "--response",
        "displacement",
        "--direction",
        "rotation",
        "--json",
    ]);
    assert!(v["peaks"][0].as_f64().unwrap() > 0.0, "{v}");
    std::fs::write(
        &spec,
        r#"{"preset": "frame40-3d", "inputs": {"eccentricity_y": {"distribution": "normal", "mean": 0, "sd": 3}}}"#,
    )
    .unwrap();
    refused(&["sample-peaks", "--spec", spec.to_str().unwrap(), "--samples", "2"], "inputs.eccentricity_y");
    std::fs::remove_dir_all(&spec_dir).ok();
    let base = &base[..9];
    refused(&[base, &["--response", "acceleration"][..]].concat(), "direction");
    refused(&[base, &["--response", "damper_force", "--direction", "x"][..]].concat(), "response");
    refused(&["sample-peaks", "--preset", "frame40-kn", "--direction", "x"], "direction");
}

#[test]
fn simulate_is_reproducible_and_honours_fixed_inputs() {
    let args =
        ["simulate", "--preset", "frame40-kn", "--seed", "4", "--duration", "30", "--fix", "wind_speed=40", "--json"];
    let a = json(&args);
    let b = json(&args);
    assert_eq!(a["peak_roof_displacement_m"], b["peak_roof_displacement_m"]);
    assert_eq!(a["inputs"]["wind_speed"].as_f64(), Some(40.0));
    assert_eq!(a["inputs"]["damper_c1"].as_f64(), Some(5.0e4));
    let slower = json(&[
        "simulate",
        "--preset",
        "frame40-kn",
        "--seed",
        "4",
        "--duration",
        "30",
        "--fix",
        "wind_speed=20",
        "--json",
    ]);
    assert!(slower["peak_roof_displacement_m"].as_f64() < a["peak_roof_displacement_m"].as_f64());
    let dir = std::env::temp_dir().join(format!("windmeta-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let csv = dir.join("run.csv");
    let out = windmeta(&["simulate", "--duration", "5", "--out", csv.to_str().unwrap()]);
    assert!(out.status.success());
    let text = std::fs::read_to_string(&csv).unwrap();
    assert_eq!(text.lines().next(), Some("t_s,displacement_40_m"));
    assert_eq!(text.lines().count(), 1 + 501);
    // A full-order run's acceleration and damper-force histories at every floor: their peaks are
    // the ones the run reports (to the file's nine significant digits).
    let full = ["simulate", "--duration", "5", "--seed", "4", "--full-order"];
    let histories = [&full[..], &["--out", csv.to_str().unwrap(), "--history", "acceleration"]].concat();
    let out = windmeta(&[&histories[..], &["--history", "damper_force", "--history-floors", "all"]].concat());
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let reported = json(&[&full[..], &["--json"]].concat());
    let text = std::fs::read_to_string(&csv).unwrap();
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    assert_eq!((header[1], header[41], header.len()), ("acceleration_1_m_s2", "damper_force_1_n", 81));
    let rows: Vec<Vec<f64>> =
        text.lines().skip(1).map(|l| l.split(',').map(|v| v.parse().unwrap()).collect()).collect();
    for (column, name) in header.iter().enumerate().skip(1) {
        let kind = if column <= 40 { "acceleration" } else { "damper_force" };
        let expected = reported["peaks"][kind]["peaks"][(column - 1) % 40].as_f64().unwrap();
        let peak = rows.iter().fold(0.0f64, |m, row| m.max(row[column].abs()));
        assert!((peak - expected).abs() <= 1e-8 * expected, "{name}: {peak} in the file, {expected} reported");
    }
    for (wrong, field) in [(["--history", "velocity"], "response"), (["--history-floors", "0"], "floor")] {
        let out = windmeta(&[&histories[..], &wrong[..]].concat());
        let message = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.code() == Some(2) && message.contains(field), "{message}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn sample_peaks_reports_every_peak_and_summaries() {
    let v = json(&[
        "sample-peaks",
        "--preset",
        "frame40-kn",
        "--samples",
        "4",
        "--duration",
        "20",
        "--seed",
        "2",
        "--json",
    ]);
    let peaks: Vec<f64> = v["peaks"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
    assert_eq!(peaks.len(), 4);
    let mean = peaks.iter().sum::<f64>() / 4.0;
    assert!((v["mean"].as_f64().unwrap() - mean).abs() < 1e-12);
    assert!(v["sd"].as_f64().unwrap() > 0.0);
    assert!(v["quantiles"]["0.5"].as_f64().is_some());
    // Same seed, same storms, whatever the thread scheduling.
    let again = json(&[
        "sample-peaks",
        "--preset",
        "frame40-kn",
        "--samples",
        "4",
        "--duration",
        "20",
        "--seed",
        "2",
        "--json",
    ]);
    assert_eq!(v["peaks"], again["peaks"]);
    let nominal = json(&["sample-peaks", "--samples", "2", "--duration", "20", "--nominal", "--json"]);
    assert_eq!(nominal["peaks"].as_array().unwrap().len(), 2);
    let group = ["sample-peaks", "--samples", "2", "--duration", "20", "--response", "damper_force", "--group", "1"];
    let envelope = json(&[&group[..], &["--json"]].concat());
    assert_eq!(envelope["response"], serde_json::json!({"kind": "damper_force", "group": 1}));
    assert!(envelope["peaks"].as_array().unwrap().iter().all(|p| p.as_f64().unwrap() > 0.0), "{envelope}");
}

#[test]
fn bad_input_is_refused_with_a_message() {
    refused(&["simulate", "--fix", "stiffness=3"], "unknown input");
    refused(&["simulate", "--fix", "wind_speed=fast"], "not a number");
    refused(&["simulate", "--fix", "wind_speed"], "NAME=VALUE");
    refused(&["simulate", "--fix", "damper_c1=-5"], "outside the support");
    refused(&["simulate", "--fix", "wind_speed=NaN"], "finite");
    refused(&["simulate", "--duration", "-1"], "duration_s");
    refused(&["simulate", "--duration", "1e9"], "duration_s");
    refused(&["simulate", "--time-step", "0"], "time_step_s");
    refused(&["simulate", "--time-step", "2"], "cut-off");
    refused(&["simulate", "--preset", "frame41"], "unknown preset");
    refused(&["modes", "--modes", "41"], "modes");
    refused(&["sample-peaks", "--samples", "0"], "samples");
    let dir = std::env::temp_dir().join(format!("windmeta-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let spec = dir.join("spec.json");
    std::fs::write(
        &spec,
        r#"{"preset": "frame40", "inputs": {"wind_speed": {"distribution": "frechet", "mean": 30}}}"#,
    )
    .unwrap();
    refused(&["simulate", "--spec", spec.to_str().unwrap()], "spec");
    std::fs::write(
        &spec,
        r#"{"structure": {"mass": [[1e5, 0], [0, 1e5]], "stiffness": [[1e8, 2e8], [2e8, 1e8]],
            "floor_elevations_m": [4, 8], "floor_widths_m": [20, 20]}}"#,
    )
    .unwrap();
    refused(&["simulate", "--spec", spec.to_str().unwrap()], "stiffness: must be positive definite");
    refused(&["simulate", "--spec", dir.join("missing.json").to_str().unwrap()], "cannot read");
    std::fs::remove_dir_all(&dir).ok();
}

/// A custom two-storey building from a spec file runs end to end.
#[test]
fn custom_structure_runs() {
    let dir = std::env::temp_dir().join(format!("windmeta-custom-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let spec = dir.join("spec.json");
    std::fs::write(
        &spec,
        r#"{"structure": {"mass": [[2e5, 0], [0, 2e5]], "stiffness": [[4e8, -2e8], [-2e8, 2e8]],
            "floor_elevations_m": [4, 8], "floor_widths_m": [20, 20],
            "dampers": [{"floor": 1, "group": 1, "cos_angle": 0.8}, {"floor": 2, "group": 1, "cos_angle": 0.8}]},
           "modes": 2, "duration_s": 20}"#,
    )
    .unwrap();
    let v = json(&["simulate", "--spec", spec.to_str().unwrap(), "--json"]);
    assert!(v["peak_roof_displacement_m"].as_f64().unwrap() > 0.0);
    assert!(v["inputs"]["damper_c1"].is_number());
    assert!(v["inputs"].get("damper_c2").is_none());
    std::fs::remove_dir_all(&dir).ok();
}

/// The second test building (`tests/fixtures/tower30.json`, written by `tower30.py`): 30 storeys
/// with a tapering stiffness, dampers in 20 storeys and at 5 outrigger levels in three groups.
/// Its first frequency is the generator's 1.30 rad/s, and a small calibration of it validates.
#[test]
fn the_second_test_building_calibrates_and_validates() {
    let spec = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures/tower30.json");
    let modes = json(&["modes", "--spec", spec, "--json"]);
    let omega = modes["frequencies_rad_s"][0].as_f64().unwrap();
    assert!((omega - 1.30).abs() < 1e-3, "{omega}");
    let dir = database("tower30");
    let model = dir.with_file_name("tower30.json");
    let model = model.to_str().unwrap();
    let calibrate = ["calibrate", "--spec", spec, "--experiments", "16", "--duration", "120", "--out", model];
    let out = windmeta(&calibrate);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let report = json(&["validate", "--model", model, "--samples", "4", "--seed", "2", "--json"]);
    let displacement = &report["responses"][0];
    assert_eq!(displacement["response"], "displacement");
    // 16 storms of 120 s fit the roof displacement to well within 2 % on fresh storms.
    assert!(displacement["median_peak_relative_error"].as_f64().unwrap() < 0.02, "{report}");
}

/// `windmeta bench --json` at a small size: every row measured, the headline figures present and
/// consistent with the rows they come from (not their values: speed is never asserted in a test).
#[test]
fn bench_reports_rows_and_headline_figures() {
    let args = [
        "bench",
        "--duration",
        "60",
        "--experiments",
        "24",
        "--samples",
        "16",
        "--hazard-samples",
        "400",
        "--sensitivity-samples",
        "16",
        "--reference-storms",
        "8",
        "--repetitions",
        "1",
        "--json",
    ];
    let report = json(&args);
    let rows = report["rows"].as_array().unwrap();
    let stage = |prefix: &str| -> f64 {
        rows.iter().find(|r| r["stage"].as_str().unwrap().starts_with(prefix)).unwrap()["median_seconds"]
            .as_f64()
            .unwrap()
    };
    assert!(rows.iter().all(|r| r["median_seconds"].as_f64().unwrap() > 0.0), "{rows:?}");
    let reduced = stage("per sample: reduced-order reference");
    let metamodel = stage("per sample: metamodel free run");
    let ratio = report["metamodel_speedup_vs_reduced_reference"].as_f64().unwrap();
    assert!((ratio - reduced / metamodel).abs() <= 1e-9 * ratio);
    assert_eq!(report["calibration_seconds"].as_f64().unwrap(), stage("calibration, K = 24"));
    assert_eq!(report["exceedance_10k_seconds"].as_f64().unwrap(), stage("exceedance curve, 16 samples"));
    assert!(stage("roof acceleration exceedance peaks, 16 samples") > 0.0);
    assert!(stage("roof RMS acceleration exceedance peaks, 16 samples") > 0.0);
    assert!(stage("drift profile, every floor") > 0.0 && stage("acceleration profile, every floor") > 0.0);
    assert!(stage("hazard curve, 400 storms, 10 return periods") > 0.0);
    assert!(stage("Sobol indices, N = 16") > 0.0);
    assert!(stage("certified exceedance curve, 16 samples, 8 reduced-order reference storms") > 0.0);
    assert!(stage("roof acceleration at 5 m/s exceedance peaks, 16 samples") > 0.0);
    let lanes = report["reference_lanes_speedup"].as_f64().unwrap();
    let (alone, in_lanes) = (
        stage("per sample: reduced-order reference, 8 storms of a design one at a time"),
        stage("per sample: reduced-order reference, the same 8 storms in vector lanes"),
    );
    assert!((lanes - alone / in_lanes).abs() <= 1e-9 * lanes);
    // Every target is reported with its figure, and none is judged at sizes it was not set for.
    let targets = report["targets"].as_array().unwrap();
    assert_eq!(targets.len(), 12, "{targets:?}");
    let spatial = stage("per sample: reduced-order reference of frame40-3d (6 modes, 160 dampers)");
    let figure =
        targets.iter().find(|t| t["figure"].as_str().unwrap().starts_with("reduced reference of frame40-3d")).unwrap();
    assert!((figure["measured"].as_f64().unwrap() - spatial / reduced).abs() <= 1e-9 * spatial / reduced);
    assert!(targets.iter().all(|t| t["met"].is_null() && t["measured"].as_f64().unwrap() > 0.0), "{targets:?}");
    let calibration = targets.iter().find(|t| t["figure"] == "calibration, K = 24").unwrap();
    assert_eq!(calibration["measured"].as_f64().unwrap(), stage("calibration, K = 24"));
    refused(&["bench", "--preset", "frame41"], "unknown preset");
}

/// A binary built for x86-64-v3 refuses a processor without it by name, with exit code 4, before
/// any of its own code runs (instead of dying of an illegal instruction), and runs on one with it:
/// the binary under QEMU's user-mode emulation of a Nehalem (SSE4.2, no AVX) and of a Haswell.
#[test]
fn an_older_processor_is_refused_by_name() {
    if !cfg!(target_feature = "avx2") {
        crate::harness::unavailable("WINDMETA_REQUIRE_QEMU", "this build does not assume x86-64-v3");
        return;
    }
    let qemu = std::path::Path::new("/usr/bin/qemu-x86_64");
    if !qemu.exists() {
        crate::harness::unavailable("WINDMETA_REQUIRE_QEMU", "no /usr/bin/qemu-x86_64 (apt install qemu-user)");
        return;
    }
    let on = |cpu: &str| {
        Command::new(qemu).args(["-cpu", cpu, env!("CARGO_BIN_EXE_windmeta"), "--version"]).output().unwrap()
    };
    let old = on("Nehalem");
    let stderr = String::from_utf8_lossy(&old.stderr);
    assert_eq!(old.status.code(), Some(4), "{stderr}");
    assert!(stderr.contains("this processor lacks avx, avx2, fma, f16c, bmi1, bmi2"), "{stderr}");
    assert!(stderr.contains("x86-64-v3") && stderr.contains("target-cpu=native"), "{stderr}");
    let new = on("Haswell");
    assert!(new.status.success(), "{}", String::from_utf8_lossy(&new.stderr));
    assert!(String::from_utf8_lossy(&new.stdout).starts_with("windmeta "));
}

/// The service's log off a terminal (a container's, a service manager's): plain lines without
/// colour codes, or on request one JSON object per line that a collector reads without rules.
#[test]
fn the_service_logs_plain_lines_or_json_off_a_terminal() {
    for format in ["text", "json"] {
        let mut server = Command::new(env!("CARGO_BIN_EXE_windmeta"))
            .args(["serve", "--listen", "127.0.0.1:0", "--log-format", format])
            .env("DATABASE_URL", format!("sqlite://{}", database(&format!("log-{format}")).display()))
            .env_remove("RUST_LOG")
            .env_remove("NO_COLOR")
            .env_remove("WINDMETA_API_KEYS")
            .stdout(Stdio::piped())
            .spawn()
            .expect("the binary starts");
        let log = BufReader::new(server.stdout.take().unwrap());
        let listening = log.lines().map_while(Result::ok).find(|line| line.contains("windmeta listening"));
        let _ = server.kill();
        let _ = server.wait();
        let line = listening.unwrap_or_else(|| panic!("{format}: the server never logged its address"));
        assert!(!line.contains('\u{1b}'), "{format}: colour codes in {line:?}");
        if format == "json" {
            let entry: Value = serde_json::from_str(&line).expect("one JSON object per line");
            assert_eq!(entry["level"], "INFO", "{entry}");
            assert!(entry["timestamp"].is_string(), "{entry}");
            assert!(entry["fields"]["address"].as_str().is_some_and(|a| a.starts_with("127.0.0.1:")), "{entry}");
        } else {
            assert!(line.contains(" INFO ") && line.contains("address=127.0.0.1:"), "{line}");
        }
    }
}

/// A 25-storey shear building whose storey stiffness falls with height (k_i = 2·10⁹ · 0.9^i N/m):
/// its 25th mode leaves the roof at rest (roof component 10⁻²² of its largest, by scipy), which
/// the damping matrix does not mind and a study retaining three modes must not refuse.
#[test]
fn a_building_whose_highest_mode_leaves_the_roof_at_rest_runs() {
    let floors = 25;
    let storey = |i: usize| 2e9 * 0.9f64.powi(i as i32);
    let mut stiffness = vec![vec![0.0; floors]; floors];
    for i in 0..floors {
        stiffness[i][i] += storey(i);
        if i + 1 < floors {
            stiffness[i][i] += storey(i + 1);
            stiffness[i][i + 1] -= storey(i + 1);
            stiffness[i + 1][i] -= storey(i + 1);
        }
    }
    let mass: Vec<Vec<f64>> =
        (0..floors).map(|i| (0..floors).map(|j| if i == j { 1e6 } else { 0.0 }).collect()).collect();
    let dampers: Vec<serde_json::Value> =
        (1..=floors).map(|f| serde_json::json!({"floor": f, "group": 1, "cos_angle": 0.8})).collect();
    let structure = serde_json::json!({
        "mass": mass, "stiffness": stiffness, "dampers": dampers,
        "floor_elevations_m": (1..=floors).map(|f| 4.0 * f as f64).collect::<Vec<_>>(),
        "floor_widths_m": vec![30.0; floors],
    });
    let dir = std::env::temp_dir().join(format!("windmeta-shear-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("spec.json");
    std::fs::write(&path, serde_json::json!({"structure": structure, "modes": 3, "duration_s": 30}).to_string())
        .unwrap();
    let three = path.to_str().unwrap();
    for order in [&[][..], &["--full-order"][..]] {
        let v = json(&[&["simulate", "--spec", three, "--json"][..], order].concat());
        assert!(v["peak_roof_displacement_m"].as_f64().is_some_and(|x| x > 0.0 && x.is_finite()), "{order:?}: {v}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// A custom three-dimensional building given storey by storey: ten equal shear storeys, whose
/// modes have the closed form ω_r = 2√(k/m)·sin((2r − 1)π/(2(2n + 1))) in each direction and in
/// twist (with k_θ and I = m(B² + D²)/12); its storms run, with its dampers along x, from a
/// random direction; a spec with both a preset and the building is refused by name.
/// The example floor force records drive the example ten-storey building (30 m along x, 20 m along
/// y, y twice as stiff, every load far below its frequencies, so quasi-static): a storm towards 80°
/// takes the records measured towards 90°, whose drag along y (up to 1.69 q·b·h) sways it more than
/// their across-wind force along x (up to 0.25 q·b·h on half the stiffness: 3.4 times at the
/// sines' joint maxima, at least twice within a 120 s window), and a storm towards 10° the 0°
/// records, the other way round (13.5 times at the maxima, at least five). A storm longer than the
/// records at its speed is refused, naming the direction.
#[test]
fn floor_force_records_drive_a_custom_building() {
    let spec = concat!(env!("CARGO_MANIFEST_DIR"), "/docs/data/tower10-3d.json");
    let records = concat!(env!("CARGO_MANIFEST_DIR"), "/docs/data/floor-records-example.json");
    let run = |direction: &str, duration: &str| {
        let fix = format!("wind_direction={direction}");
        vec![
            "simulate",
            "--spec",
            spec,
            "--wind-tunnel",
            records,
            "--fix",
            "wind_speed=30",
            "--fix",
            &fix,
            "--duration",
            duration,
            "--modes",
            "6",
            "--json",
        ]
        .into_iter()
        .map(String::from)
        .collect::<Vec<String>>()
    };
    let roof = |v: &Value, name: &str| v["peaks"][name][9].as_f64().unwrap();
    let args = run("80", "120");
    let across = json(&args.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(across["wake_loads"], "floor_force_records");
    assert_eq!(across["records_direction_deg"], 90.0);
    let (x, y) = (roof(&across, "displacement_x_m"), roof(&across, "displacement_y_m"));
    assert!(y > 2.0 * x && x > 0.0, "towards 80°: x {x}, y {y}");
    let args = run("10", "120");
    let along = json(&args.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(along["records_direction_deg"], 0.0);
    let (x, y) = (roof(&along, "displacement_x_m"), roof(&along, "displacement_y_m"));
    assert!(x > 5.0 * y && y > 0.0, "towards 10°: x {x}, y {y}");
    let args = run("10", "600");
    refused(&args.iter().map(String::as_str).collect::<Vec<_>>(), "directions[0]");
}

#[test]
fn a_custom_three_dimensional_building_runs_from_its_spec() {
    let (mass, kx, ky, kt, breadth, depth) = (1.0e6, 1.0e9, 2.0e9, 2.0e11, 30.0, 20.0);
    let storeys: Vec<Value> = (1..=10)
        .map(|j| {
            serde_json::json!({
                "elevation_m": 4.0 * j as f64, "mass_kg": mass, "stiffness_x_n_per_m": kx,
                "stiffness_y_n_per_m": ky, "torsional_stiffness_n_m_per_rad": kt,
                "plan": {"breadth_m": breadth, "depth_m": depth},
            })
        })
        .collect();
    let dampers: Vec<Value> = (1..=10)
        .flat_map(|j| {
            [10.0, -10.0].map(|y| {
                serde_json::json!({"floor": j, "group": 1, "cos_angle": 0.8, "direction_deg": 0, "position_m": [0.0, y]})
            })
        })
        .collect();
    let spec = serde_json::json!({
        "spatial_structure": {"storeys": storeys, "dampers": dampers},
        "inputs": {"damper_c1": {"distribution": "uniform", "lower": 0.0, "upper": 5.0e5}},
    });
    let dir = std::env::temp_dir().join(format!("windmeta-custom-3d-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("building.json");
    std::fs::write(&path, spec.to_string()).unwrap();
    let file = path.to_str().unwrap();
    let v = json(&["modes", "--spec", file, "--modes", "3", "--json"]);
    let w: Vec<f64> = v["frequencies_rad_s"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
    let first = |k: f64, m: f64| 2.0 * (k / m).sqrt() * (std::f64::consts::PI / 42.0).sin();
    let inertia = mass * (breadth * breadth + depth * depth) / 12.0;
    let mut expected = [first(kx, mass), first(ky, mass), first(kt, inertia)];
    expected.sort_by(f64::total_cmp);
    for (w, e) in w.iter().zip(expected) {
        assert!((w / e - 1.0).abs() < 1e-9, "{w} against {e}");
    }
    let peaks = json(&[
        "sample-peaks",
        "--spec",
        file,
        "--samples",
        "2",
        "--duration",
        "20",
        "--response",
        "corner_acceleration",
        "--json",
    ]);
    assert!(peaks["peaks"].as_array().unwrap().iter().all(|p| p.as_f64().unwrap() > 0.0), "{peaks}");
    assert_eq!(peaks["preset"], "custom");
    let both = serde_json::json!({"preset": "frame40-3d", "spatial_structure": {"storeys": storeys}});
    std::fs::write(&path, both.to_string()).unwrap();
    refused(&["modes", "--spec", file], "preset");
    let plane = serde_json::json!({"spatial_structure": {"storeys": storeys}});
    std::fs::write(&path, plane.to_string()).unwrap();
    refused(&["calibrate", "--spec", file, "--out", dir.join("m.json").to_str().unwrap()], "spatial_structure");
    std::fs::remove_dir_all(&dir).ok();
}
