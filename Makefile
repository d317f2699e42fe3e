# Everything runs from a local virtual environment installed from requirements.lock: exact versions
# with their hashes, so a fresh clone computes what the committed results in results/ say.
VENV ?= .venv
PY := $(VENV)/bin/python
ARGS ?=

.PHONY: install lock train test test-slow docs docs-check bench-quick bench clean

$(VENV)/.installed: requirements.lock
	python3 -m venv $(VENV)
	$(PY) -m pip install --quiet --disable-pip-version-check --require-hashes -r requirements.lock
	touch $@

install: $(VENV)/.installed

lock:                         ## re-resolve requirements-dev.txt (ranges) into requirements.lock (exact, hashed)
	python3 -m venv .venv-lock && .venv-lock/bin/pip install --quiet pip-tools
	.venv-lock/bin/pip-compile --quiet --generate-hashes --allow-unsafe --strip-extras --no-emit-index-url \
	  --no-emit-find-links -o requirements.lock requirements-dev.txt

train: install                ## python train.py on the default simulated scene (make train ARGS="model=resmlp")
	$(PY) train.py $(ARGS)

test: install                 ## the default test suite on both cores (< 10 min on 2 cores)
	$(PY) -m pytest -q -m "not slow" -n 2 --durations=15

test-slow: install            ## the slow tests only
	$(PY) -m pytest -q -m slow --durations=5

docs: install                 ## render every generated table of README.md and docs/ from results/ (no model runs)
	$(PY) docs/generate.py

docs-check: install           ## exit 1 if a generated table differs from what results/ renders
	$(PY) docs/generate.py --check

bench-quick: install          ## re-measure the headline numbers into results/, then re-render the docs
	CI=true $(PY) bench/quick_tour.py --quick
	CI=true OMP_NUM_THREADS=1 $(PY) bench/contacts.py --runs 3
	CI=true $(PY) bench/fidelity.py --scene all
	$(PY) docs/generate.py

bench: install                ## every bench that records results (hours: see docs/layout.md), then the docs
	CI=true $(PY) bench/quick_tour.py
	CI=true OMP_NUM_THREADS=1 $(PY) bench/contacts.py
	CI=true $(PY) bench/fidelity.py --scene all
	$(PY) docs/generate.py

clean:
	rm -rf $(VENV) .venv-lock outputs multirun .pytest_cache
