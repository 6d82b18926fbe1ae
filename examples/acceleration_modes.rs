//! Where a metamodel's roof-acceleration error comes from, mode by mode: on fresh storms, the
//! roof acceleration's peak and RMS from the reduced reference's modal motion with one mode's
//! displacements replaced by the metamodel's prediction (velocities then by central differences,
//! as the metamodel's are), against the reference's own and the metamodel's. A mode whose
//! swap alone moves the mean peak by the metamodel's bias is where the bias comes from.
//!
//! ```sh
//! cargo run --release --example acceleration_modes -- --model model.json --samples 50 [--wind-speed 60]
//! ```

use clap::Parser;
use rayon::prelude::*;
use windmeta::analysis::{Response, ResponseView};
use windmeta::dynamics::{ModalMotion, SampleModel, integrate_reduced};
use windmeta::progress::Silent;
use windmeta::surrogate::Metamodel;
use windmeta::uncertainty::{monte_carlo, rng_from_seed};
use windmeta::wind::TransformWorkspace;

#[derive(Debug, Parser)]
struct Args {
    #[arg(long)]
    model: std::path::PathBuf,
    #[arg(long, default_value_t = 50)]
    samples: usize,
    #[arg(long, default_value_t = 5)]
    seed: u64,
    /// Hold the wind speed at this value (m/s), e.g. beyond the calibration design.
    #[arg(long)]
    wind_speed: Option<f64>,
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args = Args::parse();
    let metamodel = Metamodel::from_json(&std::fs::read_to_string(&args.model)?)?;
    let study = metamodel.study()?;
    let floors = study.structure.floors();
    let responses = [Response::Acceleration { floor: floors }, Response::RmsAcceleration { floor: floors }];
    let modes = metamodel.models.len();
    let inputs = match args.wind_speed {
        Some(v) => study.inputs.clone().with_fixed("wind_speed", v)?,
        None => study.inputs.clone(),
    };
    let xs = monte_carlo(&inputs, args.samples, &mut rng_from_seed(args.seed));
    let dt = study.storm.time_step;
    // Per storm, per response: [reference, metamodel, reference with mode m swapped for m = 1..].
    let rows: Vec<Vec<Vec<f64>>> = xs
        .par_iter()
        .enumerate()
        .map_init(TransformWorkspace::default, |workspace, (k, x)| {
            let (p, coarse) =
                study.sample_storm(x, metamodel.calibration.options.wind, args.seed, k, workspace).unwrap();
            let forces = coarse.on_grid(&study.storm);
            let (sample_modes, dampers) = (study.sample_modes(&p), study.dampers(&p).unwrap());
            let reference = integrate_reduced(&sample_modes, p.damping_ratio, &dampers, &forces, dt, &Silent).unwrap();
            let predicted = metamodel.predict(&study, x, &forces).unwrap();
            let model = SampleModel::new(&sample_modes, p.damping_ratio, &dampers);
            let displacements = reference.displacements.clone();
            let mut motions = vec![reference.motion(), ModalMotion::from_displacements(predicted.clone(), dt)];
            for m in 0..modes {
                let mut swapped = displacements.clone();
                swapped[m] = predicted[m].clone();
                motions.push(ModalMotion::from_displacements(swapped, dt));
            }
            // The reference's own displacements with differenced velocities: what differencing alone does.
            motions.push(ModalMotion::from_displacements(displacements, dt));
            let views: Vec<ResponseView> = motions
                .iter()
                .map(|motion| ResponseView::new(&metamodel.modes.shapes, &study.structure, motion, &model, &forces, dt))
                .collect();
            // Mode 1's prediction in its own linear part only (−2ζω ẏ − ω² y), the dampers' forces
            // left the reference's: a = a_ref + φ₁ (−2ζω₁ Δẏ₁ − ω₁² Δy₁).
            let roof = Response::Acceleration { floor: floors };
            let reference_history = roof.history(&views[0]).unwrap();
            let (own, swapped) = (&motions[2 + modes], &motions[2]);
            let (omega, zeta) = (sample_modes.frequencies[0], p.damping_ratio);
            let phi = metamodel.modes.shapes[0][floors - 1];
            let linear_only: Vec<f64> = (0..reference_history.len())
                .map(|t| {
                    let dy = swapped.displacements[0][t] - own.displacements[0][t];
                    let dv = swapped.velocities[0][t] - own.velocities[0][t];
                    reference_history[t] + phi * (-2.0 * zeta * omega * dv - omega * omega * dy)
                })
                .collect();
            responses
                .iter()
                .map(|r| {
                    let mut row: Vec<f64> = views.iter().map(|view| r.peak(view).unwrap()).collect();
                    row.push(r.of_history(&linear_only, dt));
                    row
                })
                .collect()
        })
        .collect();
    for (j, response) in responses.iter().enumerate() {
        let mean = |c: usize| rows.iter().map(|row| row[j][c]).sum::<f64>() / rows.len() as f64;
        let reference = mean(0);
        println!(
            "{} over {} storms: mean of the reference {reference:.5} {}",
            response.describe(),
            rows.len(),
            response.unit()
        );
        println!("  metamodel, every mode predicted: {:.4} of the reference's", mean(1) / reference);
        for m in 0..modes {
            println!("  reference with mode {} predicted: {:.4}", m + 1, mean(2 + m) / reference);
        }
        println!("  reference, velocities by central differences: {:.4}", mean(2 + modes) / reference);
        println!("  reference with mode 1 predicted in its linear part only: {:.4}", mean(3 + modes) / reference);
    }
    Ok(())
}
