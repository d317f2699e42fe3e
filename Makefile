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

test: install                 ## the default test suite (not marked slow) on both cores; its time: results/test_suite.jsonl
	$(PY) -m pytest -q -m "not slow" -n 2 --durations=15

test-slow: install            ## the slow tests only
	$(PY) -m pytest -q -m slow --durations=5

docs: install                 ## render every generated table of README.md and docs/ from results/ (no model runs)
	$(PY) docs/generate.py

docs-check: install           ## exit 1 if a generated table differs from what results/ renders
	$(PY) docs/generate.py --check

# Each bench appends its records to results/<bench>.jsonl; docs/results.md lists what each one
# last cost (its records' duration). One thread per process, as train.py's default.
BENCH_ENV := CI=true OMP_NUM_THREADS=1
BENCH_TMP ?= /tmp/touchstone-bench

bench-quick: install          ## the headline numbers (tour, contact loop, fidelity, recordings vs aeon on two sets), then the docs
	$(BENCH_ENV) $(PY) bench/quick_tour.py --quick
	$(BENCH_ENV) $(PY) bench/contacts.py --runs 3
	$(BENCH_ENV) $(PY) bench/fidelity.py --scene all
	$(BENCH_ENV) $(PY) bench/tsc_peers.py --sets GunPoint BasicMotions --methods aeon:minirocket minirocket \
	  --seeds 0 1 2 --out $(BENCH_TMP)/tsc_peers_two_sets
	$(PY) docs/generate.py

bench: install                ## every bench that records (many hours on 2 cores), then the docs
	rm -rf $(BENCH_TMP) && mkdir -p $(BENCH_TMP)
	$(BENCH_ENV) $(PY) bench/quick_tour.py
	$(BENCH_ENV) $(PY) bench/contacts.py
	$(BENCH_ENV) $(PY) bench/fidelity.py --scene all
	$(BENCH_ENV) $(PY) bench/scenes.py
	$(BENCH_ENV) $(PY) bench/latency.py
	$(BENCH_ENV) $(PY) bench/soak_stream.py
	$(BENCH_ENV) $(PY) bench/threads.py
	$(BENCH_ENV) $(PY) bench/large_table.py
	$(BENCH_ENV) $(PY) train.py seed=0 hydra.run.dir=$(BENCH_TMP)/default_run
	$(BENCH_ENV) $(PY) bench/fitted_state.py $(BENCH_TMP)/default_run
	$(BENCH_ENV) $(PY) bench/blend_weights.py
	$(BENCH_ENV) $(PY) bench/blend_resampling.py
	$(BENCH_ENV) $(PY) bench/kfold_variance.py
	$(BENCH_ENV) $(PY) bench/feature_ablation.py
	$(BENCH_ENV) $(PY) bench/rubber12_repeat_variation.py
	$(BENCH_ENV) $(PY) train.py -m experiment=capacitive_force hydra.sweep.dir=$(BENCH_TMP)/capacitive_force
	$(BENCH_ENV) $(PY) bench/capacitive_force.py $(BENCH_TMP)/capacitive_force
	$(BENCH_ENV) $(PY) bench/capacitive_gp.py
	$(BENCH_ENV) $(PY) bench/taxels.py
	$(BENCH_ENV) $(PY) bench/taxels.py --covers
	$(BENCH_ENV) $(PY) bench/taxel_shear_candidates.py
	$(BENCH_ENV) $(PY) bench/ert.py
	$(BENCH_ENV) $(PY) bench/ert_localisation_floor.py
	$(BENCH_ENV) $(PY) bench/ert_vs_pyeit.py
	$(BENCH_ENV) $(PY) bench/ert_learned_validation.py
	$(BENCH_ENV) $(PY) bench/ert_off_grid.py
	$(BENCH_ENV) $(PY) bench/calibrate.py
	$(BENCH_ENV) $(PY) bench/textile_layout_physics.py
	$(BENCH_ENV) $(PY) bench/tsc_reference.py
	$(BENCH_ENV) $(PY) bench/tsc_peers.py --out $(BENCH_TMP)/tsc_peers
	$(BENCH_ENV) $(PY) bench/rocket_parity.py
	$(BENCH_ENV) $(PY) bench/onnx_ppv_floor.py
	$(BENCH_ENV) $(PY) bench/search_scaling.py
	$(BENCH_ENV) $(PY) bench/ddp_step_time.py --repeats 3
	$(BENCH_ENV) $(PY) bench/model_configs.py
	$(BENCH_ENV) $(PY) bench/reproduce.py --recordings GunPoint
	$(PY) bench/test_suite_time.py --runs 3
	$(PY) bench/test_suite_time.py --runs 3 --beside-busy
	$(PY) docs/generate.py

clean:
	rm -rf $(VENV) .venv-lock outputs multirun .pytest_cache
