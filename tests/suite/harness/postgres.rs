//! A fresh schema on the PostgreSQL at `WINDMETA_TEST_POSTGRES` (default the local server's `test`
//! database) for each test that needs one. The store's own unit tests include this file too
//! (`src/service/store/tests.rs`), so it uses only the crate's dependencies, never the crate.

const DEFAULT_POSTGRES: &str = "postgres://postgres@127.0.0.1:5432/test";

fn postgres_url() -> String {
    std::env::var("WINDMETA_TEST_POSTGRES").unwrap_or_else(|_| DEFAULT_POSTGRES.to_string())
}

/// A URL to an empty schema of its own on the test PostgreSQL, or None (with the reason
/// printed on the process's stderr, which the harness does not capture) when none is reachable.
/// With `WINDMETA_REQUIRE_POSTGRES=1` (set by CI, where a server always runs) an unreachable
/// server fails the test instead of skipping it.
pub async fn fresh_postgres() -> Option<String> {
    sqlx::any::install_default_drivers();
    let base = postgres_url();
    let admin = match sqlx::AnyPool::connect(&base).await {
        Ok(pool) => pool,
        Err(error) => {
            let why = format!("PostgreSQL at {base} is not reachable ({error})");
            assert!(
                std::env::var("WINDMETA_REQUIRE_POSTGRES").as_deref() != Ok("1"),
                "{why} (WINDMETA_REQUIRE_POSTGRES=1 requires it)"
            );
            use std::io::Write;
            let _ =
                writeln!(std::io::stderr(), "SKIPPED: {why}; set WINDMETA_REQUIRE_POSTGRES=1 to make this a failure");
            return None;
        }
    };
    drop_stale_schemas(&admin).await;
    let schema = format!("windmeta_test_{}_{}", now_ms(), uuid::Uuid::new_v4().simple());
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
    let hour_ago = now_ms() - 3_600_000;
    for row in rows {
        let name: String = row.try_get("schema_name").unwrap_or_default();
        let created = name.split('_').nth(2).and_then(|t| t.parse::<i64>().ok()).unwrap_or(0);
        if created < hour_ago {
            let _ = sqlx::query(sqlx::AssertSqlSafe(format!("DROP SCHEMA {name} CASCADE"))).execute(admin).await;
        }
    }
}

fn now_ms() -> i64 {
    std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_millis() as i64)
}
