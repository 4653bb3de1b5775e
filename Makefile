# lpfdm — build, test, demo, figures, clean. Plain g++; `make help` lists the targets.
CXX      ?= g++
CXXFLAGS ?= -O2
OMP      ?= -fopenmp
WARN      = -std=c++17 -Wall -Wextra -Wpedantic
EIGEN     = -I/usr/include/eigen3
# The unit tests see the kernel's declarations and its inline equations and helpers
# (lpfdm.hpp's LPFDM_INTERNALS) and link against its one implementation unit, tests/kernel.cpp.
TEST_DEFS = -DLPFDM_INTERNALS
LIBS      = -lfmt
OUT      ?= out
SAN_OPT  ?= -O1
SAN       = $(SAN_OPT) -g1 -fsanitize=address,undefined,float-cast-overflow -fno-omit-frame-pointer -fno-sanitize-recover=all
# Debian packages: the program needs fmt only; the pictures gnuplot; the unit tests Eigen
# (an independent eigen-solver) and doctest.
PACKAGES  = libfmt-dev
PICTURE_PACKAGES = gnuplot-nox
TESTS     = $(wildcard tests/test_*.cpp)

.PHONY: all deps picture-deps test-deps test demo quake figures verify fuzz bench clean help
all: lpfdm

help:
	@echo "make lpfdm    build the program (./lpfdm)"
	@echo "make demo     build and run the collapsing cliff, draw $(OUT)/cliff.png and $(OUT)/cliff.gif"
	@echo "make test     unit tests (-O2 and ASan+UBSan) and deck tests"
	@echo "make quake    build and run the cliff brought down by an earthquake, draw $(OUT)/quake_cliff.png and $(OUT)/quake_cliff.gif"
	@echo "make figures  run the paper's three scenes, a slope's factor of safety (its failure mechanism) and a consolidation, draw them into $(OUT)/"
	@echo "make verify   the unit tests tagged [verify], then the verification ladder (both mappings, and ADVECT FLIP, for column, PSC, footing; PSC with DAMPING WINDOW too): out/verify.tsv, work-precision and convergence plots"
	@echo "make fuzz     fuzz the deck reader with libFuzzer (FUZZ_SECONDS, default 1800)"
	@echo "make bench    particle-steps/s on the benchmark scenes (two of them whole runs), 1 and 2 threads, against the reference kernel"
	@echo "make clean    remove what the build made"

# Missing Debian packages are installed when running as root; otherwise the exact
# command is printed and the build stops. The tests also need Eigen and doctest, clang and its libFuzzer
# runtime (the fuzzing smoke of the deck reader) and OpenMP runtime (Clang's warnings,
# tests/check_warnings.sh), cmake and pkg-config (the CMake package), python3-numpy and
# python3-pandas (the point tables and histories read by both).
TEST_PACKAGES = libeigen3-dev doctest-dev clang libclang-rt-14-dev libomp-dev cmake pkg-config python3-numpy python3-pandas
define install_missing
missing=""; for p in $(1); do \
  dpkg-query -W -f='$${Status}' $$p 2>/dev/null | grep -q "ok installed" || missing="$$missing $$p"; \
done; \
if [ -n "$$missing" ]; then \
  if [ "$$(id -u)" = 0 ]; then \
    echo "installing:$$missing"; \
    apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends $$missing >/dev/null || exit 1; \
  else \
    echo "missing Debian packages:$$missing"; echo "run: sudo apt-get install$$missing"; exit 1; \
  fi; \
fi
endef
deps:
	@$(call install_missing,$(PACKAGES))
picture-deps:
	@$(call install_missing,$(PACKAGES) $(PICTURE_PACKAGES))
test-deps:
	@$(call install_missing,$(PACKAGES) $(PICTURE_PACKAGES) $(TEST_PACKAGES))

lpfdm: lpfdm.cpp lpfdm.hpp | deps
	$(CXX) $(WARN) $(CXXFLAGS) $(OMP) -o $@ lpfdm.cpp $(LIBS)

# The unit tests build as four translation units: the kernel (tests/kernel.cpp, compiled
# once, optimised: it does the tests' work), the test files but the deck reader's as one
# unit (build/o2/unit.cpp and build/san/unit.cpp, written here), the deck reader's tests,
# and doctest's main. The test files' own code runs little and compiles at -O1 (OPT, after
# CXXFLAGS, which every unit shares: they change what the header declares; -O0 under
# the sanitizers); the deck reader's 700 checks at -O0 (they run in a second, and took
# 80 s to compile at -O2). The kernel's sanitizer build is -O1 (SAN_OPT; at -O2 it took
# 270 s to compile), and the sanitizer program links against it too.
TEST_GROUP = $(filter-out tests/test_deck.cpp,$(TESTS))
TEST_OBJ  = build/o2/kernel.o build/o2/unit.o build/o2/test_deck.o build/o2/main.o build/o2/alloc_counter.o
SAN_OBJ   = build/san/kernel.o build/san/unit.o build/san/test_deck.o build/san/main.o build/san/alloc_counter.o
build/o2/unit.o: OPT = -O1
build/o2/test_deck.o: OPT = -O0
build/san/unit.o build/san/test_deck.o: SAN_OPT = -O0
build/o2/kernel.o: lpfdm.hpp
build/o2/test_deck.o build/san/test_deck.o: lpfdm.hpp tests/common.hpp
define unity
@mkdir -p $(dir $(1)); printf '#include "../../%s"\n' $(2) > $(1).tmp; \
cmp -s $(1).tmp $(1) && rm -f $(1).tmp || mv $(1).tmp $(1)
endef
.PHONY: FORCE
build/o2/unit.cpp build/san/unit.cpp: FORCE
	$(call unity,$@,$(TEST_GROUP))

build/o2/unit.o: build/o2/unit.cpp $(TEST_GROUP) tests/common.hpp lpfdm.hpp | test-deps
	$(CXX) $(WARN) -Werror $(CXXFLAGS) $(OPT) $(OMP) $(EIGEN) $(TEST_DEFS) -c -o $@ $<
build/o2/%.o: tests/%.cpp | test-deps
	@mkdir -p build/o2
	$(CXX) $(WARN) -Werror $(CXXFLAGS) $(OPT) $(OMP) $(EIGEN) $(TEST_DEFS) -c -o $@ $<

build/san/unit.o: build/san/unit.cpp $(TEST_GROUP) tests/common.hpp lpfdm.hpp | test-deps
	$(CXX) $(WARN) -Werror $(SAN) $(OMP) $(EIGEN) $(TEST_DEFS) -c -o $@ $<
build/san/%.o: tests/%.cpp | test-deps
	@mkdir -p build/san
	$(CXX) $(WARN) -Werror $(SAN) $(OMP) $(EIGEN) $(TEST_DEFS) -c -o $@ $<

build/tests: $(TEST_OBJ)
	$(CXX) $(CXXFLAGS) $(OMP) -o $@ $^ $(LIBS)

build/tests-san: $(SAN_OBJ)
	$(CXX) $(SAN) $(OMP) -o $@ $^ $(LIBS)
# The sanitizer tests' units but the kernel (tests/run.sh makes these while the sanitizer
# program's job makes the kernel, then links).
.PHONY: san-test-units
san-test-units: $(filter-out build/san/kernel.o,$(SAN_OBJ))

# The sanitizer program: lpfdm.cpp's main alone (LPFDM_KERNEL_APART) linked against the
# unit tests' sanitizer kernel, compiled once for both (it needs fmt only).
build/san/kernel.o: tests/kernel.cpp lpfdm.hpp | deps
	@mkdir -p build/san
	$(CXX) $(WARN) -Werror $(SAN) $(OMP) $(TEST_DEFS) -c -o $@ $<
build/san/lpfdm-main.o: lpfdm.cpp lpfdm.hpp | deps
	@mkdir -p build/san
	$(CXX) $(WARN) -Werror $(SAN) $(OMP) -DLPFDM_KERNEL_APART -c -o $@ lpfdm.cpp
build/lpfdm-san: build/san/lpfdm-main.o build/san/kernel.o
	$(CXX) $(SAN) $(OMP) -o $@ $^ $(LIBS)

# tests/run.sh installs the packages (test-deps) and builds the four programs as jobs of its
# queue, beside the checks that need only ./lpfdm.
test:
	@bash tests/run.sh

demo: lpfdm | picture-deps
	@mkdir -p $(OUT)
	./lpfdm -o $(OUT) decks/cliff.deck
	gnuplot -e "in='$(OUT)/cliff_points.txt'; out='$(OUT)/cliff.png'; title='Cliff failure (Fig. 5)'; frame=-1" tools/snapshot.gp
	gnuplot -e "in='$(OUT)/cliff_points.txt'; out='$(OUT)/cliff.gif'; title='Cliff failure'; delay=25" tools/animate.gp 2>/dev/null
	@echo "pictures: $(OUT)/cliff.png $(OUT)/cliff.gif"

# The cliff of Fig. 5 standing under its own weight, then shaken down (SHAKE; decks/README.md).
quake: lpfdm | picture-deps
	@mkdir -p $(OUT)
	./lpfdm -o $(OUT) decks/quake_cliff.deck
	gnuplot -e "in='$(OUT)/quake_cliff_points.txt'; out='$(OUT)/quake_cliff.png'; title='Cliff shaken down'; frame=-1" tools/snapshot.gp
	gnuplot -e "in='$(OUT)/quake_cliff_points.txt'; out='$(OUT)/quake_cliff.gif'; title='Cliff shaken down (0.4 g, 2 Hz from t = 1 s)'; delay=15" tools/animate.gp 2>/dev/null
	@echo "pictures: $(OUT)/quake_cliff.png $(OUT)/quake_cliff.gif"

# Verification ladder (resolutions, points per cell) against closed-form references.
# The unit tests tagged [verify] first: finer or longer versions of make test's cases.
verify: lpfdm build/tests | picture-deps
	OMP_NUM_THREADS=1 build/tests --no-version=1 --test-case='*[verify]*'
	@mkdir -p $(OUT)
	bash tools/verify.sh ./lpfdm $(OUT)
	VERIFY_MAPPING=SMOOTH VERIFY_APPEND=1 bash tools/verify.sh ./lpfdm $(OUT) column psc footing
	VERIFY_MAPPING=SMOOTH VERIFY_ADVECT=FLIP VERIFY_APPEND=1 bash tools/verify.sh ./lpfdm $(OUT) column psc footing
	VERIFY_WINDOW=2.4E-3 VERIFY_REPEAT=1 VERIFY_APPEND=1 bash tools/verify.sh ./lpfdm $(OUT) psc
	VERIFY_MAPPING=SMOOTH VERIFY_WINDOW=2.4E-3 VERIFY_REPEAT=1 VERIFY_APPEND=1 bash tools/verify.sh ./lpfdm $(OUT) psc
	VERIFY_MAPPING=SMOOTH VERIFY_ADVECT=FLIP VERIFY_WINDOW=2.4E-3 VERIFY_REPEAT=1 VERIFY_APPEND=1 bash tools/verify.sh ./lpfdm $(OUT) psc

# Speed on the named benchmark scenes (decks/bench_*.deck), with the reference kernel beside it.
bench: lpfdm
	bash tools/bench.sh ./lpfdm 5

# Coverage-guided fuzzing of the deck reader (clang's libFuzzer).
FUZZ_SECONDS ?= 1800
fuzz: | deps
	bash tools/fuzz.sh $(FUZZ_SECONDS)

# The paper's three experiments (Figs. 4-6) and their pictures.
figures: lpfdm | picture-deps
	@mkdir -p $(OUT)
	./lpfdm -q -o $(OUT) decks/psc.deck
	./lpfdm -q -o $(OUT) decks/cliff.deck
	./lpfdm -q -o $(OUT) decks/trapdoor.deck
	./lpfdm -q --fos -o $(OUT)/slope decks/slope.deck
	./lpfdm -q -o $(OUT) decks/consolidation.deck
	./lpfdm -q -o $(OUT) decks/drawdown.deck
	gnuplot -e "in='$(OUT)/psc_history.txt'; out='$(OUT)/psc_curve.png'; wall=1; width=0.1; height=0.2; c=9800; phi=28.648; title='Plane-strain compression (Fig. 4): Table 1 soil, scatter and softening'" tools/psc_curve.gp
	gnuplot -e "in='$(OUT)/psc_points.txt'; out='$(OUT)/psc_specimen.png'; L=0.01; mat=1; epmax=0.2; title='Plane-strain compression (Fig. 4)'" tools/specimen.gp
	gnuplot -e "in='$(OUT)/psc_points.txt'; out='$(OUT)/psc.gif'; title='Plane-strain compression'; epmax=0.05" tools/animate.gp 2>/dev/null
	gnuplot -e "in='$(OUT)/cliff_points.txt'; out='$(OUT)/cliff.png'; title='Cliff failure (Fig. 5)'; frame=-1" tools/snapshot.gp
	gnuplot -e "in='$(OUT)/cliff_points.txt'; out='$(OUT)/cliff.gif'; title='Cliff failure'; delay=25" tools/animate.gp 2>/dev/null
	gnuplot -e "in='$(OUT)/trapdoor_points.txt'; out='$(OUT)/trapdoor.png'; title='Trapdoor (Fig. 6)'; frame=-1; size='900,800'" tools/snapshot.gp
	gnuplot -e "in='$(OUT)/trapdoor_points.txt'; out='$(OUT)/trapdoor.gif'; title='Trapdoor'; delay=25" tools/animate.gp 2>/dev/null
	gnuplot -e "in='$(OUT)/slope/fails/slope_points.txt'; out='$(OUT)/slope_mechanism.png'; title='Slope 2:1 (Griffiths and Lane, ex. 1): the first trial that failed'; frame=-1; color='u'" tools/snapshot.gp
	gnuplot -e "in='$(OUT)/consolidation_points.txt'; out='$(OUT)/consolidation.png'; title='Terzaghi consolidation (consolidation.deck, 10 cells over H): pore pressure against depth'" tools/consolidation.gp
	gnuplot -e "in='$(OUT)/drawdown_points.txt'; out='$(OUT)/drawdown.png'; title='Rapid drawdown (drawdown.deck): the slope 5.5 s after its reservoir fell'; frame=-1; color='u'; size='1000,500'" tools/snapshot.gp
	@echo "figures in $(OUT)/"

clean:
	rm -rf build $(OUT) lpfdm
