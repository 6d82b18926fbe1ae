//! The committed API contract (openapi/openapi.yaml) is the one the code generates.

use std::path::Path;

#[test]
fn committed_contract_matches_the_code() {
    let generated = windmeta::service::openapi().to_yaml().expect("the document renders as YAML");
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("openapi/openapi.yaml");
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    if committed == generated {
        return;
    }
    // Asked to update, it writes the new contract and still fails: a run that found the contract
    // stale never passes, so CI cannot pass on a contract it just rewrote.
    let updated = std::env::var_os("UPDATE_OPENAPI").is_some();
    if updated {
        std::fs::write(&path, &generated).expect("openapi/openapi.yaml is writable");
    }
    panic!(
        "openapi/openapi.yaml differed from the API the code serves; {}",
        if updated {
            "it is rewritten: review the change and run the test again"
        } else {
            "review the change and run `UPDATE_OPENAPI=1 cargo test --release openapi`"
        }
    );
}
