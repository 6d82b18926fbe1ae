//! The service under test: a real server on port 0 against a real SQLite file, a client, and the
//! checks every answer gets (its status documented, errors as problem+json).

use serde_json::Value;
use std::path::PathBuf;
use std::time::{Duration, Instant};
use tokio::sync::oneshot;
use windmeta::service::{Application, Role, ServeArgs};

/// A server on port 0, running in this test's runtime until [`TestApp::stop`].
pub struct TestApp {
    pub address: String,
    /// The settings it runs with.
    pub config: ServeArgs,
    pub client: reqwest::Client,
    stop: Option<oneshot::Sender<()>>,
    server: tokio::task::JoinHandle<std::io::Result<()>>,
}

/// A fresh SQLite file for one test (`name` tells the tests of one run apart).
pub fn database(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("windmeta-api-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir.join("windmeta.db")
}

pub async fn spawn_app(db: &std::path::Path) -> TestApp {
    spawn_app_with(db, vec![], vec![]).await
}

pub async fn spawn_app_with(db: &std::path::Path, api_keys: Vec<String>, cors_origins: Vec<String>) -> TestApp {
    spawn_app_configured(db, |args| {
        args.api_keys = api_keys;
        args.cors_origins = cors_origins;
    })
    .await
}

/// Small limits so that tests can reach them; `adjust` changes what a test needs.
pub async fn spawn_app_configured(db: &std::path::Path, adjust: impl FnOnce(&mut ServeArgs)) -> TestApp {
    let mut args = ServeArgs {
        api_keys: vec![],
        cors_origins: vec![],
        listen: "127.0.0.1:0".into(),
        database_url: format!("sqlite://{}", db.display()),
        role: Role::All,
        workers: 1,
        max_body_bytes: 64 * 1024,
        max_samples: 2000,
        max_sync_samples: 2000,
        max_queued_jobs: 100,
        max_experiments: 400,
        lease_ms: 2_000,
        ..ServeArgs::default()
    };
    adjust(&mut args);
    super::logs::capture();
    let config = args.clone();
    let app = Application::build(args).await.expect("the app builds");
    let address = format!("http://{}", app.local_addr());
    let (stop, stopped) = oneshot::channel::<()>();
    let server = tokio::spawn(app.run(async move {
        let _ = stopped.await;
    }));
    TestApp { address, config, client: reqwest::Client::new(), stop: Some(stop), server }
}

/// Fails unless the API description documents `status` for the operation `path` resolves to: every
/// answer the tests see through `get` and `post` is checked, so an undocumented status cannot hide.
pub fn assert_documented(method: &str, path: &str, status: u16) {
    static SPEC: std::sync::OnceLock<Value> = std::sync::OnceLock::new();
    let spec = SPEC.get_or_init(|| serde_json::to_value(windmeta::service::openapi()).unwrap());
    let path = path.split('?').next().unwrap();
    let segments: Vec<&str> = path.split('/').collect();
    let (template, item) = spec["paths"]
        .as_object()
        .unwrap()
        .iter()
        .find(|(template, _)| {
            let parts: Vec<&str> = template.split('/').collect();
            parts.len() == segments.len()
                && parts.iter().zip(&segments).all(|(t, s)| t == s || (t.starts_with('{') && t.ends_with('}')))
        })
        .unwrap_or_else(|| panic!("{path} is not a documented path"));
    let responses = &item[method.to_lowercase()]["responses"];
    assert!(
        responses.get(status.to_string()).is_some(),
        "{method} {template} answered {status}, which is not documented"
    );
}

impl TestApp {
    pub async fn get(&self, path: &str) -> (u16, Value) {
        let r = self.client.get(format!("{}{path}", self.address)).send().await.unwrap();
        let status = r.status().as_u16();
        assert_documented("GET", path, status);
        (status, r.json().await.unwrap_or(Value::Null))
    }

    pub async fn post(&self, path: &str, body: Value) -> reqwest::Response {
        let r = self.client.post(format!("{}{path}", self.address)).json(&body).send().await.unwrap();
        assert_documented("POST", path, r.status().as_u16());
        r
    }

    /// POST with a JSON answer: its status and body.
    pub async fn post_json(&self, path: &str, body: Value) -> (u16, Value) {
        let r = self.post(path, body).await;
        (r.status().as_u16(), r.json().await.unwrap_or(Value::Null))
    }

    pub async fn wait_for(&self, id: &str, states: &[&str], limit: Duration) -> Value {
        let started = Instant::now();
        loop {
            let (_, op) = self.get(&format!("/v1/operations/{id}")).await;
            if states.contains(&op["state"].as_str().unwrap_or("")) {
                return op;
            }
            assert!(started.elapsed() < limit, "operation stuck: {op}");
            tokio::time::sleep(Duration::from_millis(200)).await;
        }
    }

    pub async fn stop(mut self) {
        let _ = self.stop.take().unwrap().send(());
        self.server.await.unwrap().unwrap();
    }
}

pub fn assert_problem(response_status: u16, content_type: &str, body: &Value, status: u16, mentions: &str) {
    assert_eq!(response_status, status, "{body}");
    assert_eq!(content_type, "application/problem+json");
    assert_eq!(body["status"], status);
    assert!(body.to_string().contains(mentions), "expected `{mentions}` in {body}");
}

pub async fn problem_details(response: reqwest::Response) -> (u16, String, Value) {
    let status = response.status().as_u16();
    let content_type =
        response.headers().get("content-type").map(|v| v.to_str().unwrap().to_string()).unwrap_or_default();
    (status, content_type, response.json().await.unwrap_or(Value::Null))
}
