# rgraph: `make run` renders the bundled surgery graph; `make test` runs the suite.
VENV := .venv
PY := $(VENV)/bin/python
RGRAPH := $(VENV)/bin/rgraph
SIZE ?= 640x360

.PHONY: setup run test test-slow fuzz lint schema bench clean

setup:
	@bash scripts/setup.sh

run: setup
	@mkdir -p out
	$(RGRAPH) run surgery --size $(SIZE) --frames 16 --out out/surgery.png --timings out/timings.json

test: setup
	$(PY) -m pytest -q -n 2 --timeout 900

test-slow: setup
	$(PY) -m pytest -q -m slow --timeout 3600

fuzz: setup
	$(PY) -m rgraph.fuzz_hostile --cases $(or $(HOSTILE_CASES),3000) --seed $(or $(SEED),1)
	RGRAPH_FUZZ_EXAMPLES=500 $(PY) -m pytest -q -m slow -k fuzz --timeout 7200

lint: setup
	$(VENV)/bin/ruff check rgraph passes tests benchmarks tools

schema: setup
	$(RGRAPH) schema > schema/rgraph.schema.json

bench: setup
	$(PY) benchmarks/compile_scaling.py
	$(PY) benchmarks/placement.py

clean:
	rm -rf out .pytest_cache build *.egg-info
