# One entry point for people and CI: `make demo`, `make test`, `make lint`, `make bench`.
PY ?= python3
VENV ?= .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.deps-installed

.PHONY: demo test test-rust test-python lint docs build bench bench-quick bench-full bench-grid clean fuzz

$(STAMP): pyproject.toml Makefile
	$(PY) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip
	$(BIN)/python -m pip install -q "maturin>=1.7,<2" "numpy>=1.24" "scipy>=1.10" \
		"pytest>=7" "hypothesis>=6" "matplotlib>=3.6" "pandas>=1.5" "ruff>=0.5" \
		"control>=0.10" "dask[array]>=2023.1" "distributed>=2023.1" "pyarrow>=12" "mypy>=1.10" "tqdm>=4.60" "threadpoolctl>=3.1" \
		"selenium>=4.10" "mkdocs>=1.5" "mkdocstrings[python]>=0.24" "pytest-xdist>=3.5"
	touch $(STAMP)

build: $(STAMP)
	$(BIN)/maturin develop --release --quiet

demo: build
	$(BIN)/python -m sysid demo

test-rust:
	cargo test --release -p sysid-core

# the tests on every core (pytest-xdist), then alone the few that time a latency (marked
# `serial`: Ctrl-C within a second), so that the others' load does not decide them; the site
# first (docs builds it after build), so that tests/test_docs_site.py checks it and nothing is
# skipped on a fresh clone
test-python: docs
	$(BIN)/python -m pytest -q -n auto -m "not serial"
	$(BIN)/python -m pytest -q -m serial

test: test-rust test-python

lint: build
	cargo fmt --all -- --check
	cargo clippy --release --all-targets -- -D warnings
	$(BIN)/ruff check python tests benches examples
	$(BIN)/python -m mypy.stubtest sysid._sysid

# the API reference and guides as a site in site/ (MkDocs + mkdocstrings; warnings are errors)
docs: build
	$(BIN)/mkdocs build --strict --quiet

bench: build
	$(BIN)/python benches/run.py

bench-quick: build
	$(BIN)/python benches/run.py --quick

# every figure of issue 16 in one run (about 25 min on 2 idle cores; parts: --parts NAME)
bench-full: build
	$(BIN)/python benches/full.py

# the peer grid of benches/run.py (hours: every tool up to 10^6 samples)
bench-grid: build
	$(BIN)/python benches/run.py --full

# Fuzz the compressors and the estimators for FUZZ_SECONDS each (needs a nightly toolchain
# and `cargo install cargo-fuzz`); a crash leaves its input in fuzz/artifacts/<target>/.
FUZZ_SECONDS ?= 60
fuzz:
	cd fuzz && for t in compressor estimators; do \
		cargo +nightly fuzz run $$t -- -max_total_time=$(FUZZ_SECONDS) -rss_limit_mb=4096 || exit 1; \
	done

clean:
	rm -rf $(VENV) target site
