//! What one core of this machine can do with the metamodel's arithmetic, against what the free run
//! does: the fused multiply-add's throughput and latency on the vectors the free run uses, and
//! the dampers' power's, each measured in a loop that does nothing else (medians of 5 runs).
//! docs/performance.md sets these against the operations a storm-step of the free run performs.
//!
//! `cargo run --release --example roofline`

use std::time::Instant;
use windmeta::dynamics::power_lanes;
use windmeta::simd::{Kernel, LANES, Lanes, Vector, run_widest};

/// Iterations of each measured loop.
const ITERATIONS: usize = 20_000_000;

/// Nanoseconds per iteration of `work`, the median of five runs.
fn nanoseconds_per_iteration(work: impl Fn() -> f64) -> f64 {
    let mut runs: Vec<f64> = (0..5)
        .map(|_| {
            let start = Instant::now();
            std::hint::black_box(work());
            start.elapsed().as_secs_f64() * 1e9 / ITERATIONS as f64
        })
        .collect();
    runs.sort_by(f64::total_cmp);
    runs[2]
}

/// `CHAINS` independent chains of fused multiply-adds on the widest vectors: with one chain the
/// loop waits on each result (latency), with many the units stay busy (throughput).
struct FusedChains<const CHAINS: usize>;

impl<const CHAINS: usize> Kernel for FusedChains<CHAINS> {
    type Output = f64;
    #[inline(always)]
    fn run<V: Vector>(self, isa: V::Isa) -> f64 {
        let (a, b) = (V::splat(isa, 0.999_999_9), V::splat(isa, 1e-9));
        let mut chains = [V::splat(isa, 1.0); CHAINS];
        for _ in 0..ITERATIONS {
            for c in chains.iter_mut() {
                *c = c.mul_add(a, b);
            }
        }
        let mut sum = 0.0;
        for c in chains {
            let mut lanes = [0.0; LANES];
            c.store(&mut lanes);
            sum += lanes.iter().sum::<f64>();
        }
        sum
    }
}

/// `CHAINS` independent chains of the dampers' power (the secant's (Δ² + κ²)^((α−1)/2) of a
/// batch), each step's argument made from the last result as the free run's is.
struct PowerChains<const CHAINS: usize>;

impl<const CHAINS: usize> Kernel for PowerChains<CHAINS> {
    type Output = f64;
    #[inline(always)]
    fn run<V: Vector>(self, _: V::Isa) -> f64 {
        let mut chains: [Lanes; CHAINS] = [[0.5; LANES]; CHAINS];
        for _ in 0..ITERATIONS / 8 {
            for c in chains.iter_mut() {
                let argument: Lanes = std::array::from_fn(|l| c[l].mul_add(1e-3, 0.25));
                *c = power_lanes(argument, -0.31);
            }
        }
        chains.iter().flatten().sum()
    }
}

fn main() {
    let fma_latency = nanoseconds_per_iteration(|| run_widest(FusedChains::<1>));
    let fma_throughput = nanoseconds_per_iteration(|| run_widest(FusedChains::<12>)) / 12.0;
    // The power loops run an eighth of the iterations.
    let power_latency = nanoseconds_per_iteration(|| run_widest(PowerChains::<1>)) * 8.0;
    let power_throughput = nanoseconds_per_iteration(|| run_widest(PowerChains::<4>)) * 8.0 / 4.0;
    println!("one core, vectors of {LANES} f64 lanes (the widest this processor has)");
    println!("| operation on one batch of {LANES} lanes | latency (ns) | throughput (ns each) |");
    println!("|---|---:|---:|");
    println!("| fused multiply-add | {fma_latency:.3} | {fma_throughput:.3} |");
    println!("| dampers' power (one secant) | {power_latency:.2} | {power_throughput:.2} |");
    println!(
        "peak: {:.1} GFLOP/s per core (2 flops per lane and fused multiply-add)",
        2.0 * LANES as f64 / fma_throughput
    );
}
