# Everything a fresh machine needs is installed by these targets (see README.md).
PYTHON ?= python3
VENV   ?= .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: demo test check bench soak figures lint typecheck protos clean screenshots

# the tests run in this many processes (pytest-xdist). CI's machine has 2 cores; a third worker
# pays because the end-to-end tests mostly wait on mission clocks and sockets rather than compute
# (one run: 319 s with 2, 213 s with 3)
TEST_JOBS ?= 3

# liaison's browser tests drive Debian's chromium (Playwright's own browser download is not used)
CHROMIUM ?= /usr/bin/chromium

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[dev]'
	touch $(STAMP)

# the _pb2 modules and .pyi stubs of our own .proto files (made by the install too; again when a
# .proto changed since, a no-op otherwise)
protos: $(STAMP)
	$(PY) -m pygoby.protobuf.generate

demo: protos
	$(PY) examples/frontseat/run_demo.py --warp 10 --duration 50
	$(PY) examples/two_vehicles/run_demo.py  # last: it ends with where its logs are

$(CHROMIUM):
	command -v apt-get >/dev/null && (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium) || echo "install chromium for liaison's browser tests"

# what CI runs: lint, format, types and every test (property tests at the light hypothesis
# profile; `make soak` runs them at full depth)
test: protos $(CHROMIUM)
	$(PY) -m ruff check src tests benchmarks examples
	$(PY) -m ruff format --check src tests benchmarks examples
	$(PY) -m mypy
	$(PY) -m pytest -q -n $(TEST_JOBS) --dist worksteal

# the edit loop's tier (< 90 s): lint and every test but the end-to-end ones (marked e2e);
# after a failure, `$(PY) -m pytest --lf` runs what failed last
check: protos
	$(PY) -m ruff check src tests benchmarks examples
	$(PY) -m pytest -q -n $(TEST_JOBS) --dist worksteal -m "not e2e"

# the README's liaison pictures, taken by the browser test against a real two-vehicle mission
screenshots: protos $(CHROMIUM)
	PYGOBY_SCREENSHOTS=$(CURDIR)/docs/images $(PY) -m pytest -q tests/topside/test_liaison_browser.py

bench: protos
	$(PY) -m pytest benchmarks -q -o addopts="" --benchmark-only --benchmark-columns=min,mean,ops,rounds

# issue 16's hostile-client and kill -9 scenarios on loopback, with their figures (not in `test`);
# SOAK_SECONDS per scenario; then every property test at full depth (HYPOTHESIS_PROFILE=ci)
SOAK_SECONDS ?= 20
soak: protos
	$(PY) -m benchmarks.soak.run --seconds $(SOAK_SECONDS)
	HYPOTHESIS_PROFILE=ci $(PY) -m pytest -q -n $(TEST_JOBS) -m hypothesis

# Figures of the examples' READMEs, regenerated from their sources (commit the result).
EXAMPLE_SWEEP := examples/netsim/sweep_range_rate
figures: protos
	rm -rf $(EXAMPLE_SWEEP)_results
	$(VENV)/bin/pygoby netsim sweep $(EXAMPLE_SWEEP).pb.cfg -o $(EXAMPLE_SWEEP)_results
	$(VENV)/bin/pygoby netsim sweep-report $(EXAMPLE_SWEEP)_results -o examples/netsim/figures
	rm -rf $(EXAMPLE_SWEEP)_results

lint: protos
	$(PY) -m ruff check src tests benchmarks examples
	$(PY) -m mypy

# mypy over src (configured in pyproject.toml), with the stubs of our generated messages
typecheck: protos
	$(PY) -m mypy

clean:
	rm -rf $(VENV) build src/*.egg-info
	find src/pygoby/protobuf -name "*_pb2.py" -o -name "*_pb2.pyi" | xargs rm -f
