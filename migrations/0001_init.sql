-- Portable SQL (SQLite and PostgreSQL): times are epoch milliseconds, ids and JSON are text.
CREATE TABLE jobs (
    id TEXT PRIMARY KEY,
    kind TEXT NOT NULL,
    state TEXT NOT NULL,
    request TEXT NOT NULL,
    progress TEXT,
    error TEXT,
    metamodel_id TEXT,
    cancel_requested INTEGER NOT NULL DEFAULT 0,
    lease_owner TEXT,
    lease_until BIGINT,
    attempts INTEGER NOT NULL DEFAULT 0,
    created_at BIGINT NOT NULL,
    started_at BIGINT,
    finished_at BIGINT
);
CREATE INDEX jobs_claim ON jobs (state, created_at);

CREATE TABLE metamodels (
    id TEXT PRIMARY KEY,
    job_id TEXT,
    preset TEXT NOT NULL,
    created_at BIGINT NOT NULL,
    body TEXT NOT NULL
);
