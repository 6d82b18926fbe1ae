//! The HTTP service (axum on tokio): calibration jobs run by workers off the async runtime, stored
//! metamodels, exceedance requests. The only module with tokio, axum and sqlx.

mod analyses;
mod cache;
mod config;
mod error;
mod exceedance;
mod jobs;
mod lease;
mod routes;
mod schema;
mod store;

pub use config::{Role, ServeArgs};
pub use routes::{openapi, openapi_for};

use crate::analysis::ClimateCoverage;
use crate::error::{Error, Result};
use crate::structure::CustomStructure;
use crate::study::{Study, StudySpec};
use crate::surrogate::{CalibrationCost, CalibrationOptions, Refinement, WindCoverage, design};
use crate::uncertainty::Marginal;
use crate::wind::WindSite;
use cache::{Loaded, LoadedMetamodels};
use routes::ApiKeys;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::net::SocketAddr;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use store::Store;
use tokio::net::TcpListener;
use tokio::sync::{Notify, Semaphore};

/// What every handler and worker shares.
#[derive(Clone)]
pub struct AppState {
    /// Jobs, tasks, idempotency keys and metamodels; shared by every replica on one database.
    store: Store,
    /// The settings the server started with: limits, budgets, lease timing.
    config: Arc<ServeArgs>,
    /// The API keys as digests (none: the API is open).
    keys: Arc<ApiKeys>,
    /// Wakes an idle worker when a job is queued (they also poll, for jobs queued elsewhere).
    wake: Arc<Notify>,
    /// Set on shutdown: readiness fails, workers stop claiming and give their jobs back, and
    /// synchronous sampling stops.
    draining: Arc<AtomicBool>,
    /// Metamodels read back from the store, with their rebuilt studies, by id; bounded.
    loaded: Arc<Mutex<LoadedMetamodels>>,
    /// One permit per synchronous sampling request allowed to run; none left means 503.
    sampling: Arc<Semaphore>,
    /// One permit per open event stream on this replica; none left means 503.
    streams: Arc<Semaphore>,
}

/// `POST /v1/calibrations`: every field optional, the paper's values by default.
#[derive(Debug, Clone, Default, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(default, deny_unknown_fields)]
pub struct CalibrationRequest {
    /// A built-in study (`GET /v1/presets`); `frame40-kn` when neither this nor `structure` is given.
    #[schema(example = "frame40-kn", pattern = "^(frame40|frame40-kn)$")]
    pub preset: Option<String>,
    /// A structure of your own instead of a preset.
    pub structure: Option<CustomStructure>,
    /// Marginals replacing the preset's, by input name (`youngs_modulus`, `mass_factor`,
    /// `damping_ratio`, `damper_c1` … `damper_c4`, `wind_speed`).
    #[schema(schema_with = schema::marginals_schema)]
    pub inputs: BTreeMap<String, Marginal>,
    pub wind: Option<WindSite>,
    /// Exponent α of the nonlinear viscous dampers, F = c·|v|^α·sign(v).
    #[schema(exclusive_minimum = 0, maximum = 2)]
    pub damper_exponent: Option<f64>,
    /// Modes kept in the reduced model (3 in the paper), at most 10 and the structure's floors.
    #[schema(minimum = 1, maximum = 10)]
    #[serde(default, deserialize_with = "crate::count::optional_count")]
    pub modes: Option<usize>,
    /// Storm length (s); 900 in the paper, at most a day. With the time step it sets the steps per
    /// storm (at most 10⁷), which with the experiments are checked against the server's budget.
    #[schema(exclusive_minimum = 0, maximum = 86400)]
    pub duration_s: Option<f64>,
    /// Time step (s); 0.01 in the paper, at least 0.1 ms, at most π/ω_up and the duration.
    #[schema(minimum = 0.0001)]
    pub time_step_s: Option<f64>,
    /// Reference runs on the Latin hypercube (K; 200 in the paper), at most the server's
    /// `--max-experiments` (1000 by default).
    #[schema(minimum = 4, maximum = 5000)]
    #[serde(default, deserialize_with = "crate::count::optional_count")]
    pub experiments: Option<usize>,
    #[serde(default, deserialize_with = "crate::count::optional_seed")]
    pub seed: Option<u64>,
    pub narx: Option<crate::surrogate::narx::NarxOptions>,
    pub pce: Option<crate::surrogate::pce::PceOptions>,
    pub refinement: Option<Refinement>,
    /// Wind speeds (m/s) the design must cover beyond the input model's spread: half the
    /// experiments spread evenly over them, the fits weighted so the expansions stay the input
    /// model's. At most one of this and `cover_climate`.
    pub cover_wind_speeds: Option<WindCoverage>,
    /// Cover a climate: from its median annual maximum speed to its speed of `annual_probability`.
    pub cover_climate: Option<ClimateCoverage>,
}

impl CalibrationRequest {
    /// The study and the options, checked; errors name the field.
    pub fn resolve(&self, config: &ServeArgs) -> Result<(Study, CalibrationOptions)> {
        let preset = if self.preset.is_none() && self.structure.is_none() {
            Some(crate::study::DEFAULT_PRESET.into())
        } else {
            self.preset.clone()
        };
        let spec = StudySpec {
            preset,
            structure: self.structure.clone(),
            inputs: self.inputs.clone(),
            wind: self.wind.clone(),
            damper_exponent: self.damper_exponent,
            modes: self.modes,
            duration_s: self.duration_s,
            time_step_s: self.time_step_s,
        };
        let study = Study::from_spec(&spec)?;
        let defaults = CalibrationOptions::default();
        let options = CalibrationOptions {
            experiments: self.experiments.unwrap_or(defaults.experiments),
            seed: self.seed.unwrap_or(defaults.seed),
            narx: self.narx.clone().unwrap_or(defaults.narx),
            pce: self.pce.clone().unwrap_or(defaults.pce),
            refinement: self.refinement.unwrap_or(defaults.refinement),
            cover_wind_speeds: match (&self.cover_wind_speeds, &self.cover_climate) {
                (Some(_), Some(_)) => {
                    return Err(Error::invalid("cover_climate", "give cover_wind_speeds or cover_climate, not both"));
                }
                (Some(speeds), None) => Some(*speeds),
                (None, Some(climate)) => Some(climate.wind_speeds("cover_climate")?),
                (None, None) => None,
            },
            ..defaults
        };
        options.validate()?;
        if options.cover_wind_speeds.is_some() {
            design(&study, &options)?; // the range inside the wind speed's support
        }
        if options.experiments > config.max_experiments {
            return Err(Error::invalid("experiments", format!("at most {} on this server", config.max_experiments)));
        }
        CalibrationCost::estimate(&study, &options, rayon::current_num_threads())
            .check(config.max_job_memory_mb as f64 * 1024.0 * 1024.0, config.max_job_steps as f64)?;
        Ok((study, options))
    }
}

/// `POST /v1/metamodels/{id}/validations`: fresh samples through the reference and the metamodel.
#[derive(Debug, Clone, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(default, deny_unknown_fields)]
pub struct ValidationRequest {
    /// Fresh Monte Carlo samples, each one reference storm.
    #[schema(minimum = 2, maximum = 5000, default = 200)]
    #[serde(deserialize_with = "crate::count::count")]
    pub samples: usize,
    #[schema(default = 1000)]
    #[serde(deserialize_with = "crate::count::seed")]
    pub seed: u64,
    /// Inputs held, by name: `{"wind_speed": 60}` validates at one end of a calibrated range.
    #[schema(schema_with = schema::fixed_inputs_schema)]
    pub fixed: BTreeMap<String, f64>,
}

impl Default for ValidationRequest {
    fn default() -> Self {
        ValidationRequest { samples: 200, seed: 1000, fixed: BTreeMap::new() }
    }
}

/// A validation as queued: the request and the metamodel it is about.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ValidationJob {
    pub metamodel_id: String,
    pub samples: usize,
    pub seed: u64,
    #[serde(default)]
    pub fixed: BTreeMap<String, f64>,
}

/// Most samples a validation job may ask for (each is one reference storm).
pub const MAX_VALIDATION_SAMPLES: usize = 5000;

/// A bound, ready-to-run service.
pub struct Application {
    listener: TcpListener,
    state: AppState,
}

impl Application {
    /// Checks the settings, connects the database (running migrations) and binds the address
    /// (port 0 for any). Bad settings are [`Error::Invalid`]; a database or address that cannot
    /// be reached is [`Error::Internal`].
    pub async fn build(config: ServeArgs) -> Result<Application> {
        config.check()?;
        let keys = ApiKeys::new(&config.api_keys)?;
        let store = Store::connect(&config.database_url)
            .await
            .map_err(|e| Error::Internal(format!("database {}: {e}", config.database_url)))?;
        let listener = TcpListener::bind(&config.listen)
            .await
            .map_err(|e| Error::Internal(format!("cannot listen on {}: {e}", config.listen)))?;
        let state = AppState {
            store,
            keys: Arc::new(keys),
            wake: Arc::new(Notify::new()),
            draining: Arc::new(AtomicBool::new(false)),
            loaded: Arc::new(Mutex::new(LoadedMetamodels::new(config.loaded_metamodels))),
            sampling: Arc::new(Semaphore::new(config.sync_request_slots())),
            streams: Arc::new(Semaphore::new(config.max_event_streams)),
            config: Arc::new(config),
        };
        Ok(Application { listener, state })
    }

    pub fn local_addr(&self) -> SocketAddr {
        self.listener.local_addr().expect("a bound listener has an address")
    }

    /// Serves until `shutdown` resolves, then drains: stops claiming, gives running jobs back to
    /// the queue, finishes open requests.
    pub async fn run(self, shutdown: impl std::future::Future<Output = ()> + Send + 'static) -> std::io::Result<()> {
        let workers = match self.state.config.role {
            Role::Api => Vec::new(),
            Role::All | Role::Worker => jobs::spawn_workers(self.state.clone(), self.state.config.workers),
        };
        let upkeep = tokio::spawn(prune_idempotency_keys(self.state.clone()));
        let draining = self.state.draining.clone();
        let app = routes::router(self.state.clone());
        axum::serve(self.listener, app)
            .with_graceful_shutdown(async move {
                shutdown.await;
                draining.store(true, Ordering::Relaxed);
            })
            .await?;
        self.state.draining.store(true, Ordering::Relaxed);
        upkeep.abort();
        for worker in workers {
            let _ = worker.await;
        }
        Ok(())
    }
}

/// How often expired idempotency keys are deleted.
const PRUNE_INTERVAL: std::time::Duration = std::time::Duration::from_secs(600);

/// Deletes expired idempotency keys now and every [`PRUNE_INTERVAL`] (expired keys are already
/// ignored when looked up; this keeps the table from growing).
async fn prune_idempotency_keys(state: AppState) {
    let mut ticker = tokio::time::interval(PRUNE_INTERVAL);
    loop {
        ticker.tick().await;
        match state.store.prune_idempotency(state.config.idempotency_keys_since_ms()).await {
            Ok(0) => {}
            Ok(pruned) => tracing::info!(pruned, "expired idempotency keys deleted"),
            Err(error) => tracing::warn!(%error, "pruning idempotency keys failed"),
        }
    }
}

async fn shutdown_signal() {
    let interrupt = async {
        let _ = tokio::signal::ctrl_c().await;
    };
    #[cfg(unix)]
    let terminate = async {
        if let Ok(mut signal) = tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate()) {
            signal.recv().await;
        }
    };
    #[cfg(not(unix))]
    let terminate = std::future::pending::<()>();
    tokio::select! {
        _ = interrupt => {}
        _ = terminate => {}
    }
    tracing::info!("shutting down");
}

/// `windmeta serve`: runs the service until interrupted.
pub fn serve(args: &ServeArgs) -> Result<String> {
    let _ = tracing_subscriber::fmt()
        .with_env_filter(tracing_subscriber::EnvFilter::try_from_default_env().unwrap_or_else(|_| "info".into()))
        .try_init();
    let runtime =
        tokio::runtime::Runtime::new().map_err(|e| Error::Internal(format!("cannot start the runtime: {e}")))?;
    runtime.block_on(async {
        let app = Application::build(args.clone()).await?;
        tracing::info!(address = %app.local_addr(), role = ?args.role, "windmeta listening");
        app.run(shutdown_signal()).await.map_err(|e| Error::Internal(format!("server: {e}")))
    })?;
    Ok("stopped".into())
}
