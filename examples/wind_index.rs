//! The wind speed's first-order Sobol index two ways, from one metamodel file: by the pick-freeze
//! estimator of `windmeta sensitivity`, and as Var(E[peak | v]) / Var(peak) from conditional
//! samples at `speeds` equiprobable speeds of the input model's wind law (`storms` storms each,
//! the conditional means' own sampling variance subtracted).
//!
//! ```sh
//! cargo run --release --example wind_index -- --model model.json --samples 4096
//! ```

use clap::Parser;
use windmeta::analysis::{Draws, OnDivergence, OnThisMachine, Response, WIND_SPEED, metamodel_sensitivity, peaks_at};
use windmeta::progress::Silent;
use windmeta::surrogate::Metamodel;
use windmeta::uncertainty::{monte_carlo, rng_from_seed};

#[derive(Debug, Parser)]
struct Args {
    #[arg(long)]
    model: std::path::PathBuf,
    /// Rows N of the Sobol analysis.
    #[arg(long, default_value_t = 4096)]
    samples: usize,
    /// Conditional speeds (equiprobable) and storms at each.
    #[arg(long, default_value_t = 64)]
    speeds: usize,
    #[arg(long, default_value_t = 200)]
    storms: usize,
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args = Args::parse();
    let metamodel = Metamodel::from_json(&std::fs::read_to_string(&args.model)?)?;
    let study = metamodel.study()?;
    let roof = Response::Displacement { floor: study.structure.floors() };
    let sobol = metamodel_sensitivity(&metamodel, &study, roof, args.samples, 1, 0.95, &OnThisMachine, &Silent)?;
    let wind = sobol.indices.iter().find(|i| i.name == WIND_SPEED).ok_or("the model has no random wind speed")?;

    let column = study.inputs.index_of(WIND_SPEED)?;
    let law = *study.inputs.marginal(WIND_SPEED)?;
    let others = monte_carlo(&study.inputs, args.storms, &mut rng_from_seed(2));
    let mut rows = Vec::with_capacity(args.speeds * args.storms);
    for k in 0..args.speeds {
        let v = law.quantile((k as f64 + 0.5) / args.speeds as f64);
        rows.extend(others.iter().map(|x| {
            let mut x = x.clone();
            x[column] = v;
            x
        }));
    }
    let storms: Vec<usize> = (0..rows.len()).collect();
    let draws = Draws { study: &study, rows: &rows, storms: &storms, seed: 3, on_divergence: OnDivergence::Fail };
    let peaks = peaks_at(&metamodel, &draws, roof, &OnThisMachine, &Silent)?;
    let n = args.storms as f64;
    let mean = |x: &[f64]| x.iter().sum::<f64>() / x.len() as f64;
    let variance = |x: &[f64]| {
        let m = mean(x);
        x.iter().map(|y| (y - m).powi(2)).sum::<f64>() / (x.len() as f64 - 1.0)
    };
    let means: Vec<f64> = peaks.chunks(args.storms).map(mean).collect();
    let within = mean(&peaks.chunks(args.storms).map(variance).collect::<Vec<_>>());
    let between = variance(&means) - within / n;
    let total = variance(&peaks);
    println!(
        "wind speed, first order: pick-freeze {:.4} [{:.4}, {:.4}] (N = {}, {} storms); \
         Var(E[peak|v])/Var(peak) {:.4} ({} speeds × {} storms)",
        wind.first_order,
        wind.first_order_ci[0],
        wind.first_order_ci[1],
        sobol.samples,
        sobol.evaluations,
        between / total,
        args.speeds,
        args.storms
    );
    Ok(())
}
