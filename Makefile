# Two entry points for a fresh machine (Python 3.11, a C compiler, make):
#   make demo   set up, then run the end-to-end job on the embedded RX90
#   make test   set up, then run the test suite
#   make docs   run every block of README.md and docs/*.md, the slow ones too, and write the
#               console blocks' output back into the pages (the fast blocks run in make test)
PYTHON ?= python3.11
VENV   ?= .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: demo test test-quick docs bench setup clean

setup: $(STAMP)

$(STAMP): pyproject.toml
	@command -v $(PYTHON) >/dev/null 2>&1 || { echo "error: $(PYTHON) not found (set PYTHON=...)"; exit 2; }
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[test]'
	@touch $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/rx90 demo --out demo-output

# PYTEST_STATUS_FILE: where to write pytest's own exit status (make only says 2); .ci/run uses it.
# TEST_WORKERS: pytest-xdist processes (one per core); a file's tests run on one worker, so its
# module fixtures are made once; tests/conftest.py names the files spread test by test and sets
# one BLAS thread per process.
TEST_WORKERS ?= auto
test: $(STAMP)
	$(PY) -m pytest -q -n $(TEST_WORKERS) --dist loadfile; rc=$$?; \
	if [ -n "$(PYTEST_STATUS_FILE)" ]; then echo $$rc > "$(PYTEST_STATUS_FILE)"; fi; \
	if [ $$rc -eq 5 ]; then echo "error: pytest collected no tests (exit 5)" >&2; fi; \
	exit $$rc

test-quick: $(STAMP)
	$(PY) -m pytest -q -n $(TEST_WORKERS) --dist loadfile -m "not slow"

docs: $(STAMP)
	$(PY) scripts/run_docs.py --all --update

bench: $(STAMP)
	$(PY) benchmarks/bench_model.py
	$(PY) benchmarks/bench_identify.py
	$(PY) benchmarks/bench_consistency.py
	$(PY) benchmarks/bench_excitation.py
	$(PY) benchmarks/compare_excitation.py
	$(PY) benchmarks/bench_rollout.py

clean:
	rm -rf $(VENV) demo-output build *.egg-info
