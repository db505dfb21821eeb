# noisefree — common tasks. `make help` lists them.
.PHONY: help run test test-rerun view bench lint layers fmt results golden vocabulary fuzz

help:
	@echo "make run    - run the SLAM system on the embedded synthetic default (release build)"
	@echo "make test   - the whole test suite (the README's test command)"
	@echo "make view   - a release binary with the Rerun recording (run --rerun FILE.rrd, view) and the viewer's venv"
	@echo "make test-rerun - the recording's tests, read back with Rerun's own decoder (rerun-sdk in target/rerun-venv)"
	@echo "make bench  - criterion benchmarks of every crate (release)"
	@echo "make lint   - cargo fmt --check + clippy -D warnings"
	@echo "make layers - import graphs of src/ and every crate: no circle; synth and ate-eval keep their layers"
	@echo "make fmt    - format the code"
	@echo "make golden - rewrite tests/golden/regression.toml (only for an intended change; see docs/development.md)"
	@echo "make vocabulary - retrain assets/vocabulary/noisefree-k10L5.voc (renders + real EuRoC frames)"
	@echo "make results - the committed synthetic sweep: all presets x 4 configs x 10 runs, then tables + figures"
	@echo "make fuzz   - every reader's fuzz target for FUZZ_SECS s (default 60) from FUZZ_SEED (default 0),"
	@echo "              one thread; findings in target/fuzz, totals appended to results/fuzz/tally.tsv"

run:
	cargo run --release -- run

test:
	cargo test --workspace

# The Rerun recording sits behind the `rerun` cargo feature (about nine minutes more of a cold
# build on two cores). The viewer and the decoder the tests read recordings back with come from
# PyPI, at the crate's version: `rerun FILE.rrd` opens a recording.
RERUN_VENV := target/rerun-venv
RERUN_SDK := rerun-sdk==0.36.3

# The marker is written only once the install succeeded, so an interrupted one is redone.
$(RERUN_VENV)/.installed:
	python3 -m venv $(RERUN_VENV)
	$(RERUN_VENV)/bin/pip install --quiet $(RERUN_SDK)
	touch $@

view: $(RERUN_VENV)/.installed
	cargo build --release --features rerun
	@echo "record: ./target/release/noisefree run --seq walking --mcor --rerun walking.rrd"
	@echo "open:   $(RERUN_VENV)/bin/rerun walking.rrd"

test-rerun: $(RERUN_VENV)/.installed
	NOISEFREE_RERUN_PYTHON=$(CURDIR)/$(RERUN_VENV)/bin/python cargo test --features rerun --test rerun_cli

bench:
	cargo bench --workspace

lint:
	cargo fmt --all -- --check
	cargo clippy --workspace --all-targets -- -D warnings

# No import circle in src/ or any crate (test code included), and the layers synth and ate-eval
# declare kept; .ci/run runs it too.
layers:
	tools/check_layers.sh

fmt:
	cargo fmt --all

results:
	cargo build --release
	./target/release/noisefree sweep --all-synthetic --configs orb,mcor,avc,mcor+avc --runs 10 --out results/synthetic
	./target/release/noisefree table results/synthetic

golden:
	cargo run --release -- regress --update

# The shipped vocabulary: 9 synthetic renderings (150 frames each; presets x trajectories, scene
# seeds 11-19, none of them a seed the tests or the regression suite run) and the 190 real
# EuRoC V1_01 frames of ../shared/data. Deterministic: the same bytes every time.
VOC_TRAIN := target/vocab-train
EUROC_HEAD := ../shared/data/euroc_v101_head/mav0
vocabulary:
	cargo build --release
	rm -rf $(VOC_TRAIN) && mkdir -p $(VOC_TRAIN)
	i=1; for spec in clean:spin kinect:rpy boundary:xyz walking:spin distorted:rpy lag:xyz occluded:spin stereo:rpy stereo:xyz; do \
	  p=$${spec%%:*}; t=$${spec##*:}; \
	  ./target/release/noisefree synth --preset $$p --trajectory $$t --frames 150 --seed $$((10+i)) --out $(VOC_TRAIN)/$$i-$$p-$$t || exit 1; \
	  i=$$((i+1)); \
	done
	./target/release/noisefree vocab train --k 10 --levels 5 --seed 0 \
	  --images $$(for d in $(VOC_TRAIN)/*/; do if [ -d $$d/rgb ]; then echo $$d/rgb; else echo $$d/mav0/cam0/data; fi; done) \
	  $(EUROC_HEAD)/cam0/data $(EUROC_HEAD)/cam1/data \
	  -o assets/vocabulary/noisefree-k10L5.voc

# Every file format noisefree reads, fuzzed (issue 45): the library readers through the fuzz
# crate's binary, the CLI's own (runs.csv, config / systems TOML, golden file, vocabulary file)
# through the binary crate's ignored test. The dev profile on purpose: arithmetic overflow
# panics there, as under cargo-fuzz's debug assertions. One thread; FUZZ_SECS is per target.
FUZZ_SECS ?= 60
FUZZ_SEED ?= 0
FUZZ_TALLY ?= results/fuzz/tally.tsv
fuzz:
	cargo build -p fuzz
	./target/debug/fuzz --target all --secs $(FUZZ_SECS) --seed $(FUZZ_SEED) --tally $(FUZZ_TALLY)
	FUZZ_SECS=$(FUZZ_SECS) FUZZ_SEED=$(FUZZ_SEED) FUZZ_TALLY=$(abspath $(FUZZ_TALLY)) \
	  cargo test -p noisefree --bin noisefree fuzz_cli_long -- --ignored --nocapture --test-threads=1
	./target/debug/fuzz --summarize $(FUZZ_TALLY)
