//! Per-realization cost of the physics at the paper's full size (40 storeys, 900 s at 100 Hz):
//! wind by both paths and both reference integrators, medians of repeated runs in one process.
//! Run with `cargo bench --bench physics`; `windmeta bench` prints the same table.

fn main() {
    let repetitions = std::env::var("BENCH_REPETITIONS").ok().and_then(|v| v.parse().ok()).unwrap_or(7);
    for preset in ["frame40", "frame40-kn"] {
        match windmeta::cli::physics_rows(preset, 900.0, repetitions) {
            Ok(rows) => println!("{}", windmeta::cli::table(preset, 900.0, &rows)),
            Err(error) => {
                eprintln!("error: {error}");
                std::process::exit(1);
            }
        }
    }
}
