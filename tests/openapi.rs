//! The committed API contract (openapi/openapi.yaml) is the one the code generates.

use std::path::Path;

#[test]
fn committed_contract_matches_the_code() {
    let generated = windmeta::service::openapi().to_yaml().expect("the document renders as YAML");
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("openapi/openapi.yaml");
    if std::env::var_os("UPDATE_OPENAPI").is_some() {
        std::fs::write(&path, &generated).expect("openapi/openapi.yaml is writable");
        return;
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        committed == generated,
        "openapi/openapi.yaml differs from the API the code serves; review the change and run \
         `UPDATE_OPENAPI=1 cargo test --release --test openapi`"
    );
}
