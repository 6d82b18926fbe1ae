"""Schemathesis hooks for windmeta's contract run.

A POST that starts work may carry an Idempotency-Key; reusing a key with another body is refused
(422, as the Idempotency-Key draft specifies), and schemathesis would reuse its generated key with
bodies that differ. Every well-formed generated key is therefore made unique per request; keys the
schema forbids are left alone, so the server's refusal of them is still tested.
"""

import re
import uuid

import schemathesis

WELL_FORMED = re.compile(r"^[!-~]{1,255}$")


@schemathesis.hook
def before_call(context, case, kwargs):
    key = (case.headers or {}).get("Idempotency-Key")
    if isinstance(key, str) and WELL_FORMED.match(key):
        case.headers["Idempotency-Key"] = f"{key[:200]}-{uuid.uuid4().hex}"
