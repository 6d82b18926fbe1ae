-- The result of jobs that produce a report rather than a metamodel (validations), as JSON text.
ALTER TABLE jobs ADD COLUMN result TEXT;
