# lsdae: `make demo` and `make test` work on a fresh clone (they create .venv on first use).
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed-stamp
DEMO   := build/demo
SCENES := SimpleDAE Robertson HelloWorldDAE

.PHONY: venv demo test fuzz bench clean

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test]'
	touch $(STAMP)

venv: $(STAMP)

# Build the example FMUs, check them, and write reports/demo/ (JSON and console output).
demo: $(STAMP)
	$(BIN)/python -m scenes.build $(SCENES) --out $(DEMO)
	$(BIN)/python -m scenes.demo_legacy $(DEMO)
	@# Two FMUs with faults, to show evidence: a wrong partial derivative, a singular dg/dw.
	$(BIN)/python -m scenes.build SimpleDAE -D DEFECT_WRONG_JACOBIAN --out build/demo-defect
	mv build/demo-defect/SimpleDAE.fmu $(DEMO)/SimpleDAE-wrong-jacobian.fmu
	$(BIN)/python -m scenes.build VanDerPolDAE --out $(DEMO)
	@mkdir -p reports/demo
	@set -e; for fmu in $(DEMO)/*.fmu; do \
	  name=$$(basename $$fmu .fmu); \
	  $(BIN)/lsdae check $$fmu --format json:reports/demo/$$name.json \
	      --format console:reports/demo/$$name.txt --color never || test $$? -eq 1; \
	  cat reports/demo/$$name.txt; \
	done
	@echo "reports written to reports/demo/"

# The whole suite. pytest exits non-zero (5) when no test is collected; that fails too.
test: $(STAMP)
	$(BIN)/python -m pytest -q -p no:cacheprovider

# The mutation test of the engine with 20 times its examples and a random seed (minutes).
fuzz: $(STAMP)
	$(BIN)/python -m pytest -q -p no:cacheprovider tests/checks/test_engine_properties.py --fuzz 20

bench: $(STAMP)
	$(BIN)/python -m bench.static_bench --out reports/bench
	$(BIN)/python -m bench.probe_bench --out reports/bench
	$(BIN)/python -m bench.sim_bench --out reports/bench
	$(BIN)/python -m bench.startup_bench --out reports/bench
	$(BIN)/python -m bench.scale_bench --out reports/bench

clean:
	rm -rf build .cache
