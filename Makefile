# Everything runs from a local virtual environment built from the repo's own requirement files.
VENV ?= .venv
PY := $(VENV)/bin/python
ARGS ?=

.PHONY: install train test test-slow clean

$(VENV)/.installed: requirements.txt requirements-dev.txt requirements-postgres.txt
	python3 -m venv $(VENV)
	$(PY) -m pip install --quiet --disable-pip-version-check -r requirements-dev.txt
	touch $@

install: $(VENV)/.installed

train: install                ## python train.py on the default simulated scene (make train ARGS="model=resmlp")
	$(PY) train.py $(ARGS)

test: install                 ## the default test suite on both cores (< 10 min on 2 cores)
	$(PY) -m pytest -q -m "not slow" -n 2 --durations=15

test-slow: install            ## the slow tests only
	$(PY) -m pytest -q -m slow --durations=5

clean:
	rm -rf $(VENV) outputs multirun .pytest_cache
