#!/usr/bin/env bash
# Proves, without a container engine, that docker/Dockerfile's build stage has everything it needs:
# the paths its COPY lines name are copied into an empty folder, and `cargo check --locked` of the
# binary runs there, as `cargo build --locked` would in the image. A target the manifest declares
# whose files are not copied (an example, a bench), or a copied path that .dockerignore leaves out,
# fails here as it would in `docker build`.
#
#   bash docker/check-context.sh          # from the repository's root
set -euo pipefail
cd "$(dirname "$0")/.."
context=$(mktemp -d)
trap 'rm -rf "$context"' EXIT
# The build stage: from the first FROM to the second.
copies=$(awk '/^FROM /{stage++} stage == 1 && /^COPY /{for (i = 2; i < NF; i++) print $i}' docker/Dockerfile)
[[ -n $copies ]] || { echo "no COPY in the Dockerfile's build stage" >&2; exit 1; }
ignored=$(grep -v -e '^#' -e '^$' .dockerignore)
for path in $copies; do
    [[ -e $path ]] || { echo "the Dockerfile copies $path, which does not exist" >&2; exit 1; }
    for pattern in $ignored; do
        if [[ $path == $pattern || $path == $pattern/* ]]; then
            echo ".dockerignore leaves $path out of the build context, and the Dockerfile copies it" >&2
            exit 1
        fi
    done
    mkdir -p "$context/$(dirname "$path")"
    cp -r "$path" "$context/$path"
done
cd "$context"
cargo check --locked --release --bin windmeta --quiet
echo "the build context is complete: $(echo $copies | tr '\n' ' ')"
