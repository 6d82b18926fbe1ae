-- Pieces of a job that any replica may run (a calibration's experiments, in chunks), leased like
-- jobs. `result` holds the piece's output, or the error when `state` is 'failed'.
CREATE TABLE tasks (
    job_id TEXT NOT NULL,
    chunk INTEGER NOT NULL,
    state TEXT NOT NULL,
    request TEXT NOT NULL,
    result TEXT,
    lease_owner TEXT,
    lease_until BIGINT,
    attempts INTEGER NOT NULL DEFAULT 0,
    PRIMARY KEY (job_id, chunk)
);
CREATE INDEX tasks_claim ON tasks (state, job_id, chunk);
