//! The HTTP service (axum on tokio): calibrations and large analyses queued as jobs that workers
//! run off the async runtime, stored metamodels, and the sampling requests answered from them. The only module with tokio, axum and sqlx.

mod analyses;
mod cache;
mod checks;
mod config;
mod demands;
mod error;
mod exceedance;
mod jobs;
mod lease;
mod rendering;
mod requests;
mod routes;
mod schema;
mod store;
mod supervision;
mod tasks;
mod watch;
mod work;

pub use config::{LogFormat, Role, ServeArgs};
pub use requests::{CalibrationRequest, MAX_VALIDATION_SAMPLES, ValidationJob, ValidationRequest};
pub use routes::{openapi, openapi_for};

use crate::error::{Error, Result};
use cache::MetamodelCache;
use routes::ApiKeys;
use std::net::SocketAddr;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
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
    metamodels: Arc<MetamodelCache>,
    /// The selection experiments of the calibrations this replica coordinates, for the structure
    /// tasks it runs itself.
    selections: Arc<tasks::HeldSelections>,
    /// One permit per synchronous sampling request allowed to run; none left means 503.
    sampling: Arc<Semaphore>,
    /// One permit per open event stream on this replica; none left means 503.
    streams: Arc<Semaphore>,
}

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
        let store =
            Store::connect(&config.database_url).await.map_err(|e| database_failure(&config.database_url, e))?;
        let listener = TcpListener::bind(&config.listen)
            .await
            .map_err(|e| Error::Internal(format!("cannot listen on {}: {e}", config.listen)))?;
        let state = AppState {
            store,
            keys: Arc::new(keys),
            wake: Arc::new(Notify::new()),
            draining: Arc::new(AtomicBool::new(false)),
            metamodels: Arc::new(MetamodelCache::new(config.loaded_metamodels)),
            selections: Arc::default(),
            sampling: Arc::new(Semaphore::new(config.sync_request_slots())),
            streams: Arc::new(Semaphore::new(config.max_event_streams)),
            config: Arc::new(config),
        };
        Ok(Application { listener, state })
    }

    /// The address bound, with the port the system chose when the settings asked for port 0.
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
        // Only workers wait for work; an API replica has nobody to wake.
        let relay = (!workers.is_empty()).then(|| {
            let (store, wake) = (self.state.store.clone(), self.state.wake.clone());
            tokio::spawn(async move { store.relay_announcements(wake).await })
        });
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
        if let Some(relay) = relay {
            relay.abort();
        }
        for worker in workers {
            let _ = worker.await;
        }
        Ok(())
    }
}

/// Why the database could not be opened, in words that say what to do: a SQLite file that cannot
/// be opened or created (SQLite's code 14) is nearly always a folder this process may not write, as
/// a container's bind mount owned by another user.
fn database_failure(url: &str, error: sqlx::Error) -> Error {
    let url = &without_password(url);
    let cannot_open = matches!(&error, sqlx::Error::Database(e) if e.code().as_deref() == Some("14"));
    match url.strip_prefix("sqlite://").filter(|_| cannot_open) {
        Some(path) => {
            let folder = std::path::Path::new(path.split('?').next().unwrap_or(path))
                .parent()
                .map_or_else(|| ".".to_string(), |p| p.display().to_string());
            Error::Internal(format!(
                "database {url}: {error}; the folder {folder} must exist and be writable by this process (in the \
                 container image: uid 10001)"
            ))
        }
        None => Error::Internal(format!("database {url}: {error}")),
    }
}

/// The database URL as an error message may show it: a password in it (`user:password@` or
/// `?password=`) replaced by `***`, since start-up errors end up in logs.
fn without_password(url: &str) -> String {
    let Ok(mut parsed) = url::Url::parse(url) else { return url.to_string() };
    let in_query = parsed.query_pairs().any(|(key, _)| key == "password");
    if parsed.password().is_none() && !in_query {
        return url.to_string();
    }
    if parsed.password().is_some() {
        let _ = parsed.set_password(Some("***"));
    }
    if in_query {
        let pairs: Vec<(String, String)> = parsed
            .query_pairs()
            .map(|(key, value)| {
                let value = if key == "password" { "***".to_string() } else { value.into_owned() };
                (key.into_owned(), value)
            })
            .collect();
        parsed.query_pairs_mut().clear().extend_pairs(pairs);
    }
    parsed.to_string()
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

/// The process's log on standard output. Colour codes only on a terminal: a container's or a
/// service manager's log keeps plain text, or JSON lines that a collector parses without rules.
fn start_logging(format: LogFormat) {
    let filter = || tracing_subscriber::EnvFilter::try_from_default_env().unwrap_or_else(|_| "info".into());
    let _ = match format {
        LogFormat::Text => tracing_subscriber::fmt()
            .with_env_filter(filter())
            .with_ansi(std::io::IsTerminal::is_terminal(&std::io::stdout()))
            .try_init(),
        LogFormat::Json => tracing_subscriber::fmt().json().with_env_filter(filter()).with_span_list(true).try_init(),
    };
}

/// `windmeta serve`: runs the service until interrupted.
pub fn serve(args: &ServeArgs) -> Result<String> {
    start_logging(args.log_format);
    let runtime =
        tokio::runtime::Runtime::new().map_err(|e| Error::Internal(format!("cannot start the runtime: {e}")))?;
    runtime.block_on(async {
        let app = Application::build(args.clone()).await?;
        tracing::info!(address = %app.local_addr(), role = ?args.role, "windmeta listening");
        app.run(shutdown_signal()).await.map_err(|e| Error::Internal(format!("server: {e}")))
    })?;
    Ok("stopped".into())
}
