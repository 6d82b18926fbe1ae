//! A bounded load test of a running windmeta, on this machine only: `clients` concurrent clients
//! send synchronous exceedance requests for `seconds` (or until `max_requests` are answered),
//! while a probe asks `/healthz` every 20 ms and, with `--calibrate`, a full-size calibration runs
//! (cancelled at the end). Prints the latency quantiles of both and the status counts.
//!
//! ```sh
//! cargo run --release -- serve &                      # the service, as the README starts it
//! cargo run --release --example load -- --metamodel ID --clients 8 --seconds 20 --calibrate
//! ```

use clap::Parser;
use serde_json::{Value, json};
use std::collections::BTreeMap;
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

#[derive(Debug, Parser)]
struct Args {
    /// The service; only loopback addresses are accepted.
    #[arg(long, default_value = "http://127.0.0.1:8080")]
    base: String,
    /// A stored metamodel to sample.
    #[arg(long)]
    metamodel: String,
    /// Concurrent clients sending exceedance requests.
    #[arg(long, default_value_t = 8)]
    clients: usize,
    /// How long the load lasts (s).
    #[arg(long, default_value_t = 20)]
    seconds: u64,
    /// Requests answered at most, over all clients.
    #[arg(long, default_value_t = 20_000)]
    max_requests: usize,
    /// Samples per exceedance request.
    #[arg(long, default_value_t = 500)]
    samples: usize,
    /// Run the paper's calibration during the load (cancelled at the end).
    #[arg(long)]
    calibrate: bool,
    /// Bearer key, when the server has keys.
    #[arg(long, env = "WINDMETA_API_KEY")]
    key: Option<String>,
}

/// Milliseconds at quantile `q` of sorted latencies.
fn quantile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    sorted[((sorted.len() - 1) as f64 * q).round() as usize]
}

fn summary(name: &str, mut latencies: Vec<f64>) -> String {
    latencies.sort_by(f64::total_cmp);
    format!(
        "{name}: {} answered, p50 {:.1} ms, p99 {:.1} ms, max {:.1} ms",
        latencies.len(),
        quantile(&latencies, 0.5),
        quantile(&latencies, 0.99),
        latencies.last().copied().unwrap_or(f64::NAN)
    )
}

#[tokio::main]
async fn main() -> Result<(), String> {
    let args = Args::parse();
    let host = args.base.trim_start_matches("http://").split([':', '/']).next().unwrap_or("");
    if !["127.0.0.1", "localhost", "[::1]"].contains(&host) {
        return Err(format!("{}: this load test only talks to this machine", args.base));
    }
    let client = reqwest::Client::builder().timeout(Duration::from_secs(120)).build().map_err(|e| e.to_string())?;
    let authorised = |request: reqwest::RequestBuilder| match &args.key {
        Some(key) => request.bearer_auth(key),
        None => request,
    };
    let calibration = if args.calibrate {
        let request = authorised(client.post(format!("{}/v1/calibrations", args.base))).json(&json!({}));
        let operation: Value =
            request.send().await.map_err(|e| e.to_string())?.json().await.map_err(|e| e.to_string())?;
        let id = operation["id"].as_str().ok_or(format!("no calibration started: {operation}"))?.to_string();
        // Let it reach its reference storms before the load starts.
        tokio::time::sleep(Duration::from_secs(3)).await;
        Some(id)
    } else {
        None
    };

    let deadline = Instant::now() + Duration::from_secs(args.seconds);
    let answered = Arc::new(AtomicUsize::new(0));
    let url = format!("{}/v1/metamodels/{}/exceedance", args.base, args.metamodel);
    let body = json!({"samples": args.samples});
    let mut workers = Vec::new();
    for _ in 0..args.clients {
        let request = authorised(client.post(&url)).json(&body);
        let answered = answered.clone();
        let max_requests = args.max_requests;
        workers.push(tokio::spawn(async move {
            let mut seen: Vec<(u16, f64)> = Vec::new();
            while Instant::now() < deadline && answered.load(Ordering::Relaxed) < max_requests {
                let started = Instant::now();
                let status = match request.try_clone().expect("a JSON request clones").send().await {
                    Ok(response) => {
                        let status = response.status().as_u16();
                        let _ = response.bytes().await;
                        status
                    }
                    Err(_) => 0,
                };
                seen.push((status, started.elapsed().as_secs_f64() * 1e3));
                answered.fetch_add(1, Ordering::Relaxed);
                if status == 503 {
                    // As Retry-After asks, scaled down: the test measures the refusals too.
                    tokio::time::sleep(Duration::from_millis(100)).await;
                }
            }
            seen
        }));
    }
    let probe = {
        let health = format!("{}/healthz", args.base);
        let client = client.clone();
        tokio::spawn(async move {
            let mut latencies = Vec::new();
            while Instant::now() < deadline {
                let started = Instant::now();
                if client.get(&health).send().await.is_ok_and(|r| r.status().is_success()) {
                    latencies.push(started.elapsed().as_secs_f64() * 1e3);
                }
                tokio::time::sleep(Duration::from_millis(20)).await;
            }
            latencies
        })
    };

    let mut statuses: BTreeMap<u16, usize> = BTreeMap::new();
    let mut answered_latencies = Vec::new();
    for worker in workers {
        for (status, ms) in worker.await.map_err(|e| e.to_string())? {
            *statuses.entry(status).or_default() += 1;
            if status == 200 {
                answered_latencies.push(ms);
            }
        }
    }
    let health = probe.await.map_err(|e| e.to_string())?;
    if let Some(id) = calibration {
        let cancel = authorised(client.post(format!("{}/v1/operations/{id}/cancel", args.base)));
        cancel.send().await.map_err(|e| e.to_string())?;
    }
    println!(
        "{} clients, {} s, {} samples per request{}",
        args.clients,
        args.seconds,
        args.samples,
        if args.calibrate { ", a calibration running" } else { "" }
    );
    println!("{}", summary("/healthz", health));
    println!("{}", summary("exceedance 200", answered_latencies));
    let counts: Vec<String> = statuses.iter().map(|(s, n)| format!("{s}: {n}")).collect();
    println!("exceedance statuses: {} (0 = no answer)", counts.join(", "));
    Ok(())
}
