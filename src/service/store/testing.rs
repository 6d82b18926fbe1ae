//! Databases for tests: a fresh SQLite file, and a fresh schema on the PostgreSQL at
//! `WINDMETA_TEST_POSTGRES` (default the local server's `test` database). Built only for the tests
//! (the `test-support` feature, which the integration tests of several processes turn on through
//! the crate's dev-dependency on itself), never into the service.

pub const DEFAULT_POSTGRES: &str = "postgres://postgres@127.0.0.1:5432/test";

pub fn postgres_url() -> String {
    std::env::var("WINDMETA_TEST_POSTGRES").unwrap_or_else(|_| DEFAULT_POSTGRES.to_string())
}

/// A URL to an empty schema of its own on the test PostgreSQL, or None (with the reason
/// printed) when none is reachable. With `WINDMETA_REQUIRE_POSTGRES=1` (set by CI, where a
/// server always runs) an unreachable server fails the test instead of skipping it.
pub async fn fresh_postgres() -> Option<String> {
    sqlx::any::install_default_drivers();
    let base = postgres_url();
    let admin = match sqlx::AnyPool::connect(&base).await {
        Ok(pool) => pool,
        Err(error) if std::env::var("WINDMETA_REQUIRE_POSTGRES").is_ok_and(|v| v == "1") => {
            panic!("PostgreSQL is required (WINDMETA_REQUIRE_POSTGRES=1) but {base} is not reachable: {error}")
        }
        Err(error) => {
            // Straight to the process's stderr: the test harness captures `eprintln!`, and a
            // skip must be seen in the run's output.
            use std::io::Write;
            let _ = writeln!(std::io::stderr(), "PostgreSQL tests SKIPPED: {base} is not reachable ({error})");
            return None;
        }
    };
    drop_stale_schemas(&admin).await;
    let schema = format!("windmeta_test_{}_{}", super::now_ms(), uuid::Uuid::new_v4().simple());
    if let Err(error) = sqlx::query(sqlx::AssertSqlSafe(format!("CREATE SCHEMA {schema}"))).execute(&admin).await {
        panic!("cannot create the test schema {schema} on {base}: {error}");
    }
    let separator = if base.contains('?') { '&' } else { '?' };
    Some(format!("{base}{separator}options=-c%20search_path%3D{schema}"))
}

/// Test schemas are named by their creation time; those older than an hour are left-overs.
async fn drop_stale_schemas(admin: &sqlx::AnyPool) {
    use sqlx::Row;
    let Ok(rows) = sqlx::query(
        "SELECT CAST(nspname AS TEXT) AS schema_name FROM pg_namespace WHERE nspname LIKE 'windmeta_test_%'",
    )
    .fetch_all(admin)
    .await
    else {
        return;
    };
    let hour_ago = super::now_ms() - 3_600_000;
    for row in rows {
        let name: String = row.try_get("schema_name").unwrap_or_default();
        let created = name.split('_').nth(2).and_then(|t| t.parse::<i64>().ok()).unwrap_or(0);
        if created < hour_ago {
            let _ = sqlx::query(sqlx::AssertSqlSafe(format!("DROP SCHEMA {name} CASCADE"))).execute(admin).await;
        }
    }
}

#[cfg(test)]
pub async fn stores() -> Vec<(&'static str, super::Store)> {
    let dir = std::env::temp_dir().join(format!("windmeta-store-{}", uuid::Uuid::new_v4().simple()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut stores =
        vec![("sqlite", super::Store::connect(&format!("sqlite://{}", dir.join("t.db").display())).await.unwrap())];
    if let Some(url) = fresh_postgres().await {
        stores.push(("postgres", super::Store::connect(&url).await.unwrap()));
    }
    stores
}
