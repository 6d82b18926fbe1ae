//! `windmeta serve` settings, as flags or environment variables.

use crate::error::{Error, Result};
use clap::{Args, Parser, ValueEnum};

/// How `windmeta serve` writes its log.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum LogFormat {
    /// Lines for people: colour on a terminal, plain text elsewhere.
    Text,
    /// One JSON object per line, with the request or job spans, for log collectors.
    Json,
}

/// What a replica does, so that request handling and heavy work can scale apart.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Role {
    /// The API and the workers.
    All,
    /// The API only: jobs are queued for worker replicas.
    Api,
    /// Workers only, with health and metrics endpoints for the orchestrator.
    Worker,
}

/// The settings of `windmeta serve`: what it listens on and stores in, what it does, and the
/// bounds on every request's and job's cost.
#[derive(Debug, Clone, Args)]
pub struct ServeArgs {
    /// Address to listen on (port 0: any free port).
    #[arg(long, env = "WINDMETA_LISTEN", default_value = "127.0.0.1:8080")]
    pub listen: String,
    /// Database: an SQLite file (created if missing; one replica), or postgres://… shared by
    /// several replicas.
    #[arg(long, env = "DATABASE_URL", default_value = "sqlite://windmeta.db")]
    pub database_url: String,
    /// What this replica does.
    #[arg(long, env = "WINDMETA_ROLE", value_enum, default_value_t = Role::All)]
    pub role: Role,
    /// The log's format (standard output; `RUST_LOG` filters it).
    #[arg(long, env = "WINDMETA_LOG_FORMAT", value_enum, default_value_t = LogFormat::Text)]
    pub log_format: LogFormat,
    /// Jobs and tasks this replica runs at once (each uses every core through rayon).
    #[arg(long, env = "WINDMETA_WORKERS", default_value_t = 1)]
    pub workers: usize,
    /// Largest request body accepted (bytes).
    #[arg(long, env = "WINDMETA_MAX_BODY_BYTES", default_value_t = 4 * 1024 * 1024)]
    pub max_body_bytes: usize,
    /// Most storms an exceedance request may sample (the other analyses are bounded by
    /// `--max-analysis-storms`).
    #[arg(long, env = "WINDMETA_MAX_SAMPLES", default_value_t = 20_000)]
    pub max_samples: usize,
    /// Most metamodel storms one hazard, fragility, sensitivity, serviceability or sweep request
    /// may run, counted over all its wind speeds, swept values or Sobol blocks (about 35 s of two
    /// cores at full size for 100 000).
    #[arg(long, env = "WINDMETA_MAX_ANALYSIS_STORMS", default_value_t = 100_000)]
    pub max_analysis_storms: usize,
    /// Most storms one certified request may run through the reference model (each about as
    /// costly as a few hundred metamodel storms); at most 5 000.
    #[arg(long, env = "WINDMETA_MAX_REFERENCE_STORMS", default_value_t = 1_000)]
    pub max_reference_storms: usize,
    /// Sampling requests (exceedance, hazard, fragility, sensitivity, serviceability, sweep) of
    /// up to this many metamodel storms are answered at once; larger ones, certified ones and any
    /// with `Prefer: respond-async` run as operations. A demand sample, always answered at once,
    /// may have at most this many storms.
    #[arg(long, env = "WINDMETA_MAX_SYNC_SAMPLES", default_value_t = 2_000)]
    pub max_sync_samples: usize,
    /// Jobs that may wait in the queue; beyond, new work is refused with 503 and `Retry-After`.
    #[arg(long, env = "WINDMETA_MAX_QUEUED_JOBS", default_value_t = 100)]
    pub max_queued_jobs: usize,
    /// Most experiments a calibration may ask for.
    #[arg(long, env = "WINDMETA_MAX_EXPERIMENTS", default_value_t = 1000)]
    pub max_experiments: usize,
    /// A job's lease (ms): a worker that stops renewing it for this long loses the job.
    #[arg(long, env = "WINDMETA_LEASE_MS", default_value_t = 30_000)]
    pub lease_ms: i64,
    /// Bearer API keys, comma separated; when given, every /v1 request needs one.
    #[arg(long, env = "WINDMETA_API_KEYS", value_delimiter = ',', hide_env_values = true)]
    pub api_keys: Vec<String>,
    /// Origins allowed by CORS, comma separated (none: no CORS headers).
    #[arg(long, env = "WINDMETA_CORS_ORIGINS", value_delimiter = ',')]
    pub cors_origins: Vec<String>,
    /// Sampling requests answered at once at the same time, on every sampling route (0: one per
    /// core); beyond, 503 with `Retry-After`. Each uses every core, so more only queue inside the
    /// process.
    #[arg(long, env = "WINDMETA_MAX_SYNC_REQUESTS", default_value_t = 0)]
    pub max_sync_requests: usize,
    /// A sampling request answered at once that has not been answered after this many seconds is
    /// cancelled and answered 503 (ask for fewer storms, or for an operation).
    #[arg(long, env = "WINDMETA_SYNC_TIMEOUT_S", default_value_t = 60)]
    pub sync_timeout_s: u64,
    /// Operation event streams (SSE) open at once on this replica; beyond, 503 with `Retry-After`.
    #[arg(long, env = "WINDMETA_MAX_EVENT_STREAMS", default_value_t = 256)]
    pub max_event_streams: usize,
    /// Hours an `Idempotency-Key` is remembered; older keys are pruned and may be used again.
    #[arg(long, env = "WINDMETA_IDEMPOTENCY_TTL_H", default_value_t = 24)]
    pub idempotency_ttl_h: u64,
    /// Stored metamodels kept loaded in memory (least recently used are dropped first).
    #[arg(long, env = "WINDMETA_LOADED_METAMODELS", default_value_t = 16)]
    pub loaded_metamodels: usize,
    /// Memory a job may plan to hold (MiB), estimated from the request before it is queued.
    #[arg(long, env = "WINDMETA_MAX_JOB_MEMORY_MB", default_value_t = 4096)]
    pub max_job_memory_mb: usize,
    /// Reference storm steps a job may integrate in all (a calibration's experiments or a
    /// validation's samples, times the steps per storm), checked before it is queued. The paper's
    /// calibration needs 1.8·10⁷ (about a minute on 2 cores); the default allows 55 times that.
    #[arg(long, env = "WINDMETA_MAX_JOB_STEPS", default_value_t = 1_000_000_000)]
    pub max_job_steps: u64,
}

impl Default for ServeArgs {
    /// The settings as `windmeta serve` takes them with no flags (environment variables apply).
    fn default() -> Self {
        #[derive(Parser)]
        struct Command {
            #[command(flatten)]
            args: ServeArgs,
        }
        Command::parse_from(["windmeta"]).args
    }
}

impl ServeArgs {
    /// Synchronous sampling requests admitted at once.
    pub fn sync_request_slots(&self) -> usize {
        match self.max_sync_requests {
            0 => std::thread::available_parallelism().map_or(1, |n| n.get()),
            n => n,
        }
    }

    /// Idempotency keys recorded before this instant (epoch ms) have expired.
    pub fn idempotency_keys_since_ms(&self) -> i64 {
        let ttl_ms = self.idempotency_ttl_h.saturating_mul(3_600_000).min(i64::MAX as u64) as i64;
        super::store::now_ms().saturating_sub(ttl_ms)
    }

    /// Settings that cannot work are refused before anything starts.
    pub fn check(&self) -> Result<()> {
        if self.workers == 0 && self.role != Role::Api {
            return Err(Error::invalid("workers", "at least one worker is needed"));
        }
        for (field, value) in [
            ("max_body_bytes", self.max_body_bytes),
            ("max_samples", self.max_samples),
            ("max_analysis_storms", self.max_analysis_storms),
            ("max_reference_storms", self.max_reference_storms),
            ("max_queued_jobs", self.max_queued_jobs),
            ("max_experiments", self.max_experiments),
            ("max_event_streams", self.max_event_streams),
            ("loaded_metamodels", self.loaded_metamodels),
            ("max_job_memory_mb", self.max_job_memory_mb),
            ("max_job_steps", self.max_job_steps as usize),
        ] {
            if value == 0 {
                return Err(Error::invalid(field, "must be at least 1"));
            }
        }
        if self.lease_ms < 1000 {
            return Err(Error::invalid("lease_ms", "must be at least 1000 (leases are renewed every second)"));
        }
        if self.sync_timeout_s == 0 {
            return Err(Error::invalid("sync_timeout_s", "must be at least 1"));
        }
        Ok(())
    }
}
