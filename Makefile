# noisefree — common tasks. `make help` lists them.
.PHONY: help run test bench lint fmt results golden

help:
	@echo "make run    - run the SLAM system on the embedded synthetic default (release build)"
	@echo "make test   - the whole test suite (the README's test command)"
	@echo "make bench  - criterion benchmarks of every crate (release)"
	@echo "make lint   - cargo fmt --check + clippy -D warnings"
	@echo "make fmt    - format the code"
	@echo "make golden - rewrite tests/golden/regression.toml (only for an intended change; see README)"
	@echo "make results - the committed synthetic sweep: all presets x 4 configs x 10 runs, then tables + figures"

run:
	cargo run --release -- run

test:
	cargo test --workspace

bench:
	cargo bench --workspace

lint:
	cargo fmt --all -- --check
	cargo clippy --workspace --all-targets -- -D warnings

fmt:
	cargo fmt --all

results:
	cargo build --release
	./target/release/noisefree sweep --all-synthetic --configs orb,mcor,avc,mcor+avc --runs 10 --out results/synthetic
	./target/release/noisefree table results/synthetic

golden:
	cargo run --release -- regress --update
