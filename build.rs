//! Re-embeds the migrations when they change (sqlx::migrate! reads them at compile time), and links
//! the processor check into the binaries of a build that assumes x86-64-v3 (see
//! `src/simd/require_x86_64_v3.c`).
fn main() {
    println!("cargo:rerun-if-changed=migrations");
    println!("cargo:rerun-if-changed=src/simd/require_x86_64_v3.c");
    let arch = std::env::var("CARGO_CFG_TARGET_ARCH").unwrap_or_default();
    let features = std::env::var("CARGO_CFG_TARGET_FEATURE").unwrap_or_default();
    if arch == "x86_64" && features.split(',').any(|f| f == "avx2") {
        // The check is compiled for the baseline x86-64: cc would otherwise pass the build's
        // `-C target-cpu` on as `-march`.
        let objects = cc::Build::new()
            .file("src/simd/require_x86_64_v3.c")
            .inherit_rustflags(false)
            .flag("-march=x86-64")
            .compile_intermediates();
        for object in objects {
            // An object on the link line is always linked (from an archive it would be dropped,
            // since nothing refers to the constructor).
            println!("cargo:rustc-link-arg-bins={}", object.display());
        }
    }
}
