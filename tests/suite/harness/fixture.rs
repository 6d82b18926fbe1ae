//! The metamodel that every test which only needs one shares: frame40-kn, 32 Latin-hypercube
//! experiments of 120 s storms, seed 1, calibrated once per run in this process. Only the tests
//! about calibration calibrate; the others sample this one, through the library or stored in
//! their server's database as a calibration job would have stored it.

use super::app::TestApp;
use std::sync::OnceLock;
use windmeta::progress::Silent;
use windmeta::study::Study;
use windmeta::surrogate::{CalibrationOptions, Metamodel, calibrate};

/// Storm length of the fixture's experiments (s).
pub const STORM_S: f64 = 120.0;

/// The fixture and the study it was calibrated on (the preset with 120 s storms).
pub fn metamodel() -> &'static (Metamodel, Study) {
    static FIXTURE: OnceLock<(Metamodel, Study)> = OnceLock::new();
    FIXTURE.get_or_init(|| {
        let study = Study::preset("frame40-kn").unwrap().with_storm(STORM_S, 0.01).unwrap();
        let options = CalibrationOptions { experiments: 32, seed: 1, ..Default::default() };
        let metamodel = calibrate(&study, &options, &Silent).expect("the fixture calibrates");
        (metamodel, study)
    })
}

/// Stores the fixture in `app`'s database and returns its id. `storm_s` changes the length of the
/// storms it samples (the NARX models do not depend on it): 900 s makes sampling take the paper's
/// time per storm.
pub async fn install(app: &TestApp, storm_s: f64) -> String {
    install_at(&app.config.database_url, storm_s).await
}

/// Stores the fixture in the database at `database_url` (as [`install`]).
pub async fn install_at(database_url: &str, storm_s: f64) -> String {
    let mut metamodel = tokio::task::block_in_place(|| metamodel().0.clone());
    metamodel.study.duration_s = Some(storm_s);
    let body = serde_json::to_string(&metamodel).unwrap();
    let id = uuid::Uuid::new_v4().to_string();
    sqlx::any::install_default_drivers();
    let pool = sqlx::AnyPool::connect(database_url).await.expect("the test database opens");
    sqlx::query("INSERT INTO metamodels (id, job_id, preset, created_at, body) VALUES ($1, NULL, $2, $3, $4)")
        .bind(&id)
        .bind("frame40-kn")
        .bind(std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).unwrap().as_millis() as i64)
        .bind(body)
        .execute(&pool)
        .await
        .expect("the fixture is stored");
    pool.close().await;
    id
}
