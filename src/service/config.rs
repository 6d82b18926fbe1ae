//! `windmeta serve` settings, as flags or environment variables.

use clap::{Args, ValueEnum};

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
    /// Calibration jobs run at once (each uses every core through rayon).
    #[arg(long, env = "WINDMETA_WORKERS", default_value_t = 1)]
    pub workers: usize,
    /// Largest request body accepted (bytes).
    #[arg(long, env = "WINDMETA_MAX_BODY_BYTES", default_value_t = 4 * 1024 * 1024)]
    pub max_body_bytes: usize,
    /// Most samples an exceedance request may ask for.
    #[arg(long, env = "WINDMETA_MAX_SAMPLES", default_value_t = 20_000)]
    pub max_samples: usize,
    /// Exceedance requests up to this many samples are answered at once; larger ones (and any
    /// with `Prefer: respond-async`) run as operations.
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
}
