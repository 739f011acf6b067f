# `make demo` and `make test` each do the whole set-up on a fresh machine.
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed
# The one place versions are pinned; torch's pin is read from it for the CPU build below.
PINS   := constraints.txt
TORCH  := $(shell sed -n 's/^torch==//p' $(PINS))
export MUJOCO_GL ?= egl

.PHONY: install demo test lint bench weights clean

$(STAMP): pyproject.toml $(PINS) scripts/setup_system.sh
	bash scripts/setup_system.sh
	test -x $(PY) || python3 -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	# The CPU build of torch first: a plain resolve may pick a GPU build with gigabytes of CUDA wheels.
	$(PY) -m pip install -q "torch==$(TORCH)" || $(PY) -m pip install -q "torch==$(TORCH)+cpu"
	$(PY) -m pip install -q -c $(PINS) -e '.[dev]'
	touch $(STAMP)

install: $(STAMP)

# Ray, for the tests of `afford generate --ray`; the core install and the demo do without it.
CLUSTER := $(VENV)/.cluster
$(CLUSTER): $(STAMP)
	$(PY) -m pip install -q -c $(PINS) -e '.[dev,cluster]'
	touch $(CLUSTER)

# The learned planner (paper II.D) with the weights shipped in the package: no training step.
# Task 03 needs a non-canonical effect: a cup at the end of a block balanced on one support tips
# it, so the block is laid across both supports first (the symbolic baseline's plans all fail).
DEMO_TASK := tasks/paper/03-stable-base.json

demo: install
	$(VENV)/bin/afford scene --seed 7 --out out/scene.png
	$(VENV)/bin/afford demo --seed 7 --steps 4 --out out/demo.png
	@# The plan is executed and judged; a miss (exit 1) is a result to look at, not a broken demo.
	$(VENV)/bin/afford plan --task $(DEMO_TASK) --planner learned --out out/plan \
		|| echo "the learned plan missed the goal: see out/plan/"

# Two processes: most tests wait on one core (MuJoCo, a subprocess's start-up), so two share the machine well.
# Each runs torch on one thread (tests/conftest.py), and OpenMP threads that wait sleep rather
# than spin: two processes spinning for two cores each made torch ten times slower.
test: install $(CLUSTER)
	OMP_WAIT_POLICY=PASSIVE $(PY) -m pytest -q -n 2

lint: install
	$(VENV)/bin/ruff check src tests benchmarks
	$(VENV)/bin/ruff format --check src tests benchmarks

bench: install
	$(PY) benchmarks/sim_speed.py
	$(PY) benchmarks/generate_speed.py
	$(PY) benchmarks/recognition_speed.py
	$(PY) benchmarks/prediction_speed.py
	$(PY) benchmarks/learned_planning.py
	$(VENV)/bin/afford bench tasks --planner all
	$(VENV)/bin/afford bench random --n 100 --seed 0 --max-steps 2 --planner all
	$(VENV)/bin/afford bench random --n 100 --seed 0 --max-steps 3 --planner all

# Every shipped net made again from its recipe (afford/recipes/): the data, the training runs, the
# calibrations and the exports, into runs/made-weights/. About 14 hours on 2 cores; each stage
# leaves a stamp in runs/stamps/, so running it again skips what is done and resumes the rest.
weights: install
	$(VENV)/bin/afford weights make

clean:
	rm -rf $(VENV) out
