# Shortcuts only: every recipe is a plain cargo (or script) command from the README and docs.

# Render the default scene (the preprint's Lambert Cornell box).
render:
    cargo run --release -- render scenes/cornell-lambert.toml

# The test suite, exactly as CI runs it.
test:
    cargo test --workspace --release

# Formatting, lints and tests: what .ci/run does.
ci:
    bash .ci/run

# The divan benchmarks of the parts (rays, photons, camera, weights).
bench:
    cargo bench -p bdpm-suite

# The preprint's two paper runs of docs/performance.md.
paper:
    cargo run --release -- render scenes/preprint/cornell-lambert.toml --mode optimal --resolution 512x512 -o out/paper-lambert.exr
    cargo run --release -- render scenes/preprint/cornell-glossy.toml --mode optimal --resolution 512x512 -o out/paper-glossy.exr

# Render the bit-check set into DIR (compare two sets with scripts/bit-check.sh compare A B).
bit-check dir:
    cargo build --release
    scripts/bit-check.sh render {{dir}}
