# hgym: everything the project needs is built from here. Only the Rust toolchain, gcc and
# Python 3.11 are assumed. Builds go to a cache outside the clone so that fresh clones (CI)
# rebuild incrementally.

CARGO_TARGET_DIR ?= $(HOME)/.cache/hgym-target
export CARGO_TARGET_DIR
CARGO ?= cargo
HGYM := $(CARGO_TARGET_DIR)/release/hgym
LEVEL ?= default
# Python tools the tests read our files with (the `mcap` reader; pandas, pyarrow and `datasets`
# for exported Parquet datasets), in a venv outside the clone.
VENV ?= $(HOME)/.cache/hgym-venv
PYTHON ?= python3

# `!(x <= limit)` is how the checks refuse NaN along with values out of range (a NaN compares
# false): the lint that asks for partial_cmp there would make each check longer, not clearer.
CLIPPY_ALLOW := -A clippy::neg_cmp_op_on_partial_ord

.PHONY: all setup build test validate bench nightly lint fmt clean help leaderboard peers roofline python mpi

help:
	@echo "make validate   build, then validate the D2Q9 solver on the cylinder at Re 100 (LEVEL=$(LEVEL); the rest: make nightly)"
	@echo "make test       unit, exact-solution, CLI and schema tests (coarse, fast)"
	@echo "make bench      hgym bench lbm: MLUPS against the measured memory bandwidth"
	@echo "make roofline   hgym's copy bandwidth (the bench's roofline) beside STREAM's C copy, alternating"
	@echo "make nightly    validations (default level), benchmarks, short trainings, leaderboard; results/nightly/summary.md"
	@echo "make peers      install the peers hgym bench --peer runs beside ours (SB3, hydrogym[jax]; ~7 GB)"
	@echo "make mpi        install Open MPI (Debian packages), build the MPI solver test and run it on 2 and 3 ranks"
	@echo "make python     build the Python package (python/, an abi3 wheel) and install it into the test venv"
	@echo "make lint       rustfmt and clippy"
	@echo "make leaderboard  aggregate results/ into results/LEADERBOARD.md"

all: build

setup: $(VENV)/.installed
	@command -v $(CARGO) >/dev/null || { echo "cargo not found: install Rust from https://rustup.rs"; exit 2; }
	@command -v cc >/dev/null || { echo "a C compiler (gcc) is needed for some crates"; exit 2; }

$(VENV)/.installed: scripts/requirements-test.txt
	@command -v $(PYTHON) >/dev/null || { echo "python3 not found (Python 3.11 is assumed)"; exit 2; }
	$(PYTHON) -m venv $(VENV)
	$(VENV)/bin/pip install --quiet --disable-pip-version-check -r $<
	@touch $@

# The peers `hgym bench agents|kolmogorov|channel --peer` time beside ours, in a
# venv of their own: hydrogym 1.0.0 pins huggingface-hub 0.16 and pandas 2.3, which break the
# `datasets` the tests read exports with. The gymnax 1.0.1 incompatibility of hydrogym 1.0.0 is adapted
# in scripts/peers/hydrogym_kolmogorov.py, not patched into the installed files.
PEERS_VENV ?= $(HOME)/.cache/hgym-peers

peers: $(PEERS_VENV)/.installed

$(PEERS_VENV)/.installed: scripts/peers/requirements.txt
	@command -v $(PYTHON) >/dev/null || { echo "python3 not found (Python 3.11 is assumed)"; exit 2; }
	$(PYTHON) -m venv $(PEERS_VENV)
	$(PEERS_VENV)/bin/pip install --quiet --disable-pip-version-check -r $<
	$(PEERS_VENV)/bin/python -c "import stable_baselines3, torch, hydrogym.jax.envs.kolmogorov"
	@touch $@

build: setup
	$(CARGO) build --release --locked

test: setup python
	HGYM_PYTHON=$(VENV)/bin/python $(CARGO) test --release --locked --workspace -- --show-output
	HGYM=$(HGYM) $(VENV)/bin/python -m pytest -q python/tests

# The Python package: `import hgym` registers every ID with Gymnasium. maturin builds the abi3
# wheel (a workspace of its own in python/, so the root's tests never link libpython); pip
# installs it into the test venv. Users run `pip install ./python` instead.
WHEELS := $(CARGO_TARGET_DIR)/wheels
python: setup build
	$(VENV)/bin/maturin build --quiet --release --locked -m python/Cargo.toml -o $(WHEELS) -i $(VENV)/bin/python
	$(VENV)/bin/pip install --quiet --disable-pip-version-check --force-reinstall --no-deps --no-index --find-links $(WHEELS) hgym

# The main job, under 10 minutes on 2 cores at the default level: the Re 100 cylinder against
# the literature. Every other case runs in `make nightly` (`hgym validate cylinder|pinball|square`).
validate: build
	$(HGYM) validate cylinder_re100 --level $(LEVEL)

bench: build
	$(HGYM) bench lbm

# The roofline check: hgym's copy loop against STREAM's C copy compiled here, same threads,
# alternating pairs (bandwidth drifts by +-20 % from minute to minute).
$(CARGO_TARGET_DIR)/stream_copy: benchmarks/stream/copy.c
	$(CC) -O3 -march=native -fopenmp $< -o $@

# The solver split over MPI ranks (the `mpi` feature, rsmpi): Debian's Open MPI and libclang (for
# rsmpi's bindings) are installed if missing. Checks, 2 and 3 ranks against one process, bitwise
# (exit 1 if they differ): the 3D and 2D solvers alone (examples/mpi_split.rs), a 3D and a 2D
# validation case through the whole command line, `mpirun -np N hgym-mpi validate`
# (scripts/mpi_check.sh), and training on a 3D and a 2D environment (scripts/mpi_train_check.sh). The
# default build needs none of this; `hgym-mpi` is built beside `hgym`, not over it.
MPIRUN := mpirun --allow-run-as-root --oversubscribe --bind-to none
MPI_SPLIT := $(CARGO_TARGET_DIR)/release/examples/mpi_split
HGYM_MPI := $(CARGO_TARGET_DIR)/release/hgym-mpi

mpi: build
	@dpkg -s libopenmpi-dev openmpi-bin libclang-dev >/dev/null 2>&1 || { \
		SUDO=$$( [ "$$(id -u)" = 0 ] || echo sudo ); \
		$$SUDO apt-get install -y -q libopenmpi-dev openmpi-bin libclang-dev || \
		{ $$SUDO apt-get update -q && $$SUDO apt-get install -y -q libopenmpi-dev openmpi-bin libclang-dev; }; }
	$(CARGO) build --release --locked -p hgym-solvers --features mpi --example mpi_split
	$(CARGO) build --release --locked --features mpi --bin hgym-mpi
	$(MPIRUN) -np 2 $(MPI_SPLIT)
	$(MPIRUN) -np 3 $(MPI_SPLIT)
	HGYM=$(HGYM) HGYM_MPI=$(HGYM_MPI) MPIRUN="$(MPIRUN)" scripts/mpi_check.sh tests/cases/sphere_mpi.toml
	HGYM=$(HGYM) HGYM_MPI=$(HGYM_MPI) MPIRUN="$(MPIRUN)" scripts/mpi_check.sh tests/cases/cylinder_mpi.toml
	HGYM=$(HGYM) HGYM_MPI=$(HGYM_MPI) MPIRUN="$(MPIRUN)" scripts/mpi_train_check.sh tests/cases/mpi_train.toml
	HGYM=$(HGYM) HGYM_MPI=$(HGYM_MPI) MPIRUN="$(MPIRUN)" scripts/mpi_train_check.sh tests/cases/mpi_train2d.toml Cylinder_2D_Re100

roofline: build $(CARGO_TARGET_DIR)/stream_copy
	HGYM=$(HGYM) C_COPY=$(CARGO_TARGET_DIR)/stream_copy scripts/roofline.sh

nightly: build python
	HGYM=$(HGYM) scripts/nightly.sh

leaderboard: build
	$(HGYM) leaderboard > /dev/null
	@echo "wrote results/leaderboard.json, results/LEADERBOARD.md, results/leaderboard/*.png"

lint:
	$(CARGO) fmt --all -- --check
	$(CARGO) fmt --manifest-path python/Cargo.toml -- --check
	$(CARGO) clippy --release --workspace --all-targets -- -D warnings $(CLIPPY_ALLOW)
	$(CARGO) clippy --release --locked --manifest-path python/Cargo.toml -- -D warnings $(CLIPPY_ALLOW)

fmt:
	$(CARGO) fmt --all
	$(CARGO) fmt --manifest-path python/Cargo.toml

clean:
	$(CARGO) clean
