//! The method's costs at the paper's full size (40 storeys, 900 s at 100 Hz, K = 200, 10 000
//! samples), medians of repeated runs in one process: the same report as `windmeta bench`.
//! Run with `cargo bench --bench physics`; BENCH_PRESET, BENCH_REPETITIONS, BENCH_EXPERIMENTS,
//! BENCH_SAMPLES, BENCH_HAZARD_SAMPLES, BENCH_SENSITIVITY_SAMPLES and BENCH_REFERENCE_STORMS change the
//! sizes.

/// The allocator `windmeta` itself runs on (see `src/main.rs`), so that the figures are the same.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() {
    let var = |name: &str, default: usize| std::env::var(name).ok().and_then(|v| v.parse().ok()).unwrap_or(default);
    let args = windmeta::cli::BenchArgs {
        preset: std::env::var("BENCH_PRESET").unwrap_or_else(|_| "frame40-kn".into()),
        repetitions: var("BENCH_REPETITIONS", 7),
        duration: 900.0,
        experiments: var("BENCH_EXPERIMENTS", 200),
        samples: var("BENCH_SAMPLES", 10_000),
        hazard_samples: var("BENCH_HAZARD_SAMPLES", 20_000),
        sensitivity_samples: var("BENCH_SENSITIVITY_SAMPLES", 4096),
        reference_storms: var("BENCH_REFERENCE_STORMS", 200),
        json: false,
    };
    match windmeta::cli::bench_report(&args) {
        Ok(report) => println!("{}", windmeta::cli::table(&report)),
        Err(error) => {
            eprintln!("error: {error}");
            std::process::exit(1);
        }
    }
}
