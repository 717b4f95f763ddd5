# hgym: everything the project needs is built from here. Only the Rust toolchain, gcc and
# Python 3.11 are assumed. Builds go to a cache outside the clone so that fresh clones (CI)
# rebuild incrementally.

CARGO_TARGET_DIR ?= $(HOME)/.cache/hgym-target
export CARGO_TARGET_DIR
CARGO ?= cargo
HGYM := $(CARGO_TARGET_DIR)/release/hgym
LEVEL ?= default

.PHONY: all setup build test validate bench nightly lint fmt clean help

help:
	@echo "make validate   build, then validate the D2Q9 solver on the cylinder cases (LEVEL=$(LEVEL))"
	@echo "make test       unit, exact-solution, CLI and schema tests (coarse, fast)"
	@echo "make bench      hgym bench lbm: MLUPS against the measured memory bandwidth"
	@echo "make nightly    long checks: fine-level validation and the benchmark"
	@echo "make lint       rustfmt and clippy"

all: build

setup:
	@command -v $(CARGO) >/dev/null || { echo "cargo not found: install Rust from https://rustup.rs"; exit 2; }
	@command -v cc >/dev/null || { echo "a C compiler (gcc) is needed for some crates"; exit 2; }

build: setup
	$(CARGO) build --release --locked

test: setup
	$(CARGO) test --release --locked --workspace -- --show-output

validate: build
	$(HGYM) validate cylinder --level $(LEVEL)

bench: build
	$(HGYM) bench lbm

nightly: build
	$(HGYM) validate cylinder --level fine --out results/nightly/validation
	$(HGYM) bench lbm

lint:
	$(CARGO) fmt --all -- --check
	$(CARGO) clippy --release --workspace --all-targets -- -D warnings

fmt:
	$(CARGO) fmt --all

clean:
	$(CARGO) clean
