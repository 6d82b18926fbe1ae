//! The stored metamodels: their JSON bodies and summaries.

use super::Store;
use sqlx::Row;

/// A stored metamodel's summary.
#[derive(Debug, Clone)]
pub struct MetamodelRow {
    pub id: String,
    pub job_id: Option<String>,
    pub preset: String,
    pub created_at: i64,
}

impl Store {
    pub async fn metamodel_body(&self, id: &str) -> Result<Option<String>, sqlx::Error> {
        let row = sqlx::query("SELECT body FROM metamodels WHERE id = $1").bind(id).fetch_optional(&self.pool).await?;
        row.map(|r| r.try_get("body")).transpose()
    }

    pub async fn metamodel_exists(&self, id: &str) -> Result<bool, sqlx::Error> {
        let row = sqlx::query("SELECT id FROM metamodels WHERE id = $1").bind(id).fetch_optional(&self.pool).await?;
        Ok(row.is_some())
    }

    pub async fn metamodels(&self, limit: i64, offset: i64) -> Result<Vec<MetamodelRow>, sqlx::Error> {
        let rows = sqlx::query(
            "SELECT id, job_id, preset, created_at FROM metamodels ORDER BY created_at DESC, id LIMIT $1 OFFSET $2",
        )
        .bind(limit)
        .bind(offset)
        .fetch_all(&self.pool)
        .await?;
        rows.iter()
            .map(|r| {
                Ok(MetamodelRow {
                    id: r.try_get("id")?,
                    job_id: r.try_get("job_id")?,
                    preset: r.try_get("preset")?,
                    created_at: r.try_get("created_at")?,
                })
            })
            .collect()
    }

    pub async fn delete_metamodel(&self, id: &str) -> Result<bool, sqlx::Error> {
        let done = sqlx::query("DELETE FROM metamodels WHERE id = $1").bind(id).execute(&self.pool).await?;
        Ok(done.rows_affected() == 1)
    }
}
