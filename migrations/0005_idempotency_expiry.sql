-- Idempotency keys expire; the pruning deletes by age.
CREATE INDEX idempotency_created ON idempotency (created_at);
