# lsdae: `make demo` and `make test` work on a fresh clone (they create .venv on first use).
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed-stamp
DEMO   := build/demo
SCENES := SimpleDAE Robertson HelloWorldDAE

.PHONY: venv demo test fuzz bench mutation mutation-self clean

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

# The whole suite, on TEST_JOBS processes (pytest-xdist; CI has 2 cores; TEST_JOBS=0 runs it in
# this process). pytest exits non-zero (5) when no test is collected; that fails too.
# --dist worksteal: a worker that runs out of tests takes half of the other's queue, so neither
# waits a minute at the end for the other's last long tests. PYTHONDONTWRITEBYTECODE is
# cleared for the run: every probe check starts a worker process that imports conformance/,
# and without .pyc files each of them (about 500 in the suite) compiles it again (0.2 s each).
TEST_JOBS ?= 2
TEST_DIST := $(if $(filter 0,$(TEST_JOBS)),,--dist worksteal)
test: $(STAMP)
	PYTHONDONTWRITEBYTECODE= $(BIN)/python -m pytest -q -p no:cacheprovider -n $(TEST_JOBS) $(TEST_DIST)

# The mutation test of the engine with 20 times its examples and a random seed (minutes).
fuzz: $(STAMP)
	$(BIN)/python -m pytest -q -p no:cacheprovider tests/run/test_engine_properties.py tests/run/test_engine_hostile_values.py --fuzz 20

bench: $(STAMP)
	$(BIN)/python -m bench.static_bench --out reports/bench
	$(BIN)/python -m bench.probe_bench --out reports/bench
	$(BIN)/python -m bench.sim_bench --out reports/bench
	$(BIN)/python -m bench.startup_bench --out reports/bench
	$(BIN)/python -m bench.modes_bench --out reports/bench
	$(BIN)/python -m bench.scale_bench --out reports/bench

# The mutation campaign of the scenes' C code (issue 20): sample, build, oracle, lsdae check,
# verdicts, and detection against time; writes reports/mutation/ (about 25 min on 2 cores).
# Exits 1 while a survivor has no verdict in bench/mutation/verdicts.toml (docs/mutation.md).
mutation: $(STAMP)
	$(BIN)/python -m bench.mutation --fresh --out reports/mutation --stubs build/mutation-stubs.toml

# Mutation testing of lsdae's own Python code with mutmut 3: each package against its
# own tests, on 2 processes; writes reports/mutation-self/. Incremental: mutmut runs again only
# the mutants of changed functions (build/mutation-self/). Options through MUTATION_SELF_ARGS,
# e.g. MUTATION_SELF_ARGS="--packages numerics" or "--sample 200 --seed 1"; exits 1 while a
# survivor has no verdict in bench/mutation_self/<package>.toml (docs/mutation-self.md).
MUTATION_SELF_ARGS ?=
mutation-self: $(STAMP)
	$(BIN)/python -m scripts.mutation_self $(MUTATION_SELF_ARGS)

clean:
	rm -rf build .cache
