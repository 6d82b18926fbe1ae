-- Idempotency-Key: the first request under a key starts the work; retries get the same operation.
CREATE TABLE idempotency (
    idempotency_key TEXT NOT NULL,
    endpoint TEXT NOT NULL,
    request TEXT NOT NULL,
    operation_id TEXT NOT NULL,
    created_at BIGINT NOT NULL,
    PRIMARY KEY (idempotency_key, endpoint)
);
