# noisefree — common tasks. `make help` lists them.
.PHONY: help run test bench lint fmt tables

help:
	@echo "make run    - run the SLAM system on the embedded synthetic default (release build)"
	@echo "make test   - the whole test suite (the README's test command)"
	@echo "make bench  - criterion benchmarks of every crate (release)"
	@echo "make lint   - cargo fmt --check + clippy -D warnings"
	@echo "make fmt    - format the code"

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
