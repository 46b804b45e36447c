# Weathering: particle-driven weathering masks.
#   make          build build/weathering (installs missing Debian packages first)
#   make test     build and run the test suite
#   make test-blender
#                 docs/mask.md's Blender recipe, run headless in Blender
#   make test-cluster
#                 2 x 2 tiles as a Slurm job array on a one-node Slurm cluster
#                 started on this machine (docs/cluster.md)
#   make run      run the shipped default scene into out/building/
#   make gallery  every preset on every shipped model: docs/images/gallery.png
#   make previews the other pictures of docs/images, from today's code
#   make bench    benchmarks (speed and memory targets)
#   make sanitize, make tsan, make valgrind, make fuzz
#                 the reliability checks CI runs (docs/reliability.md)
#   make mpi      build-mpi/weathering, built with Open MPI (docs/scale-out.md)
#   make test-mpi the MPI program's outputs for 1 to 4 ranks against the normal one's
# BUILD=dir puts every build product in another folder.

BUILD ?= build
CC ?= cc
SCENE ?= xml_scenes/building.xml

# Debian packages the build, the tests and the viewer need.
DEB_PACKAGES := gcc make pkg-config libopenexr-dev libxml2-dev libxml2-utils \
    libosmesa6-dev libglfw3-dev libgl-dev libassimp-dev libcglm-dev libpng-dev xvfb xauth python3

CFLAGS ?= -O2 -g
WARN := -std=c11 -Wall -Wextra -pedantic -Wshadow -Wstrict-prototypes
DEFS := -D_POSIX_C_SOURCE=200809L
FPFLAGS := -fno-math-errno -ffp-contract=fast
INCLUDES := -Isrc -I$(BUILD)/gen -I/usr/include/OpenEXR -I/usr/include/libxml2
ALL_CFLAGS = $(WARN) $(DEFS) $(FPFLAGS) $(INCLUDES) $(CFLAGS) -MMD -MP -pthread
LIBS := -lOpenEXRCore-3_1 -lxml2 -lassimp -lOSMesa -lpng -lm -lpthread

# The library's layers are the folders of src/ (docs/architecture.md); the
# command line is cli/.
LIB_SRC := $(wildcard src/*/*.c)
LIB_OBJ := $(LIB_SRC:src/%.c=$(BUILD)/obj/%.o)
CLI_SRC := $(wildcard cli/*.c)
CLI_OBJ := $(CLI_SRC:cli/%.c=$(BUILD)/obj/cli/%.o)
TEST_SRC := $(wildcard tests/test_*.c)
TEST_BIN := $(TEST_SRC:tests/%.c=$(BUILD)/tests/%)
TEST_SUPPORT_OBJ := $(BUILD)/obj/tests/ensure.o
BENCH_SRC := $(wildcard tests/bench/bench_*.c)
BENCH_BIN := $(BENCH_SRC:tests/bench/%.c=$(BUILD)/bench/%)
# Only the benchmarks need these: Embree 3 is the exact-geometry reference
# (tests/bench/bench_embree.c); the library and the tests never link it.
BENCH_DEB_PACKAGES := libembree-dev
BENCH_LIBS := -lembree3
BENCH_CSV = $(BUILD)/bench/results.csv
SHADERS := $(wildcard shaders/*.glsl)
VIEWER_SRC := $(wildcard viewer/*.c)
VIEWER_OBJ := $(VIEWER_SRC:viewer/%.c=$(BUILD)/obj/viewer/%.o)
VIEWER_BIN := $(if $(VIEWER_SRC),$(BUILD)/weathering-viewer)
# Every viewer file but main.c makes the viewer's library, which the program
# and tests/test_viewer.c link.
VIEWER_LIB_OBJ := $(filter-out $(BUILD)/obj/viewer/main.o,$(VIEWER_OBJ))
# The viewer draws with the system's GL (GLFW); it never links OSMesa, and runs
# `weathering bake` in a child process when a scene's maps are still to bake.
VIEWER_LIBS := -lglfw -lGL -lOpenEXRCore-3_1 -lxml2 -lpng -lm -lpthread

.PHONY: all deps bench-deps test test-fast test-blender test-cluster run bench bench-build clean sanitize tsan fuzz valgrind gallery previews \
    mpi mpi-deps test-mpi
all: $(BUILD)/weathering $(VIEWER_BIN)

# Installs whatever Debian package is missing (apt-get update first), as root or
# through sudo. Checked on every make: dpkg -s is quick.
define install_missing
	@missing=""; for p in $(1); do \
	    dpkg -s $$p >/dev/null 2>&1 || missing="$$missing $$p"; done; \
	if [ -n "$$missing" ]; then \
	    echo "installing missing Debian packages:$$missing"; \
	    sudo=""; [ "$$(id -u)" -eq 0 ] || sudo=sudo; \
	    $$sudo apt-get update -q && \
	    DEBIAN_FRONTEND=noninteractive $$sudo apt-get install -y -q $$missing; \
	fi
endef
deps:
	$(call install_missing,$(DEB_PACKAGES))

$(BUILD)/obj/%.o: src/%.c | deps
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) -c $< -o $@

$(BUILD)/obj/cli/%.o: cli/%.c | deps
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) -c $< -o $@

$(BUILD)/obj/tests/%.o: tests/%.c | deps
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) -Itests -c $< -o $@

# GLSL sources are compiled into the binaries (build/gen/shaders.h).
$(BUILD)/gen/shaders.h: $(SHADERS) shaders/embed.sh
	@mkdir -p $(dir $@)
	sh shaders/embed.sh $@ $(SHADERS)

$(LIB_OBJ): $(BUILD)/gen/shaders.h

$(BUILD)/obj/viewer/%.o: viewer/%.c $(BUILD)/gen/shaders.h | deps
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) -Iviewer -c $< -o $@

$(BUILD)/libweathering-viewer.a: $(VIEWER_LIB_OBJ)
	@mkdir -p $(dir $@)
	rm -f $@
	ar rcs $@ $^

$(BUILD)/weathering-viewer: $(BUILD)/obj/viewer/main.o $(BUILD)/libweathering-viewer.a \
    $(BUILD)/libweathering.a
	$(CC) $(ALL_CFLAGS) -o $@ $^ $(VIEWER_LIBS)

$(BUILD)/obj/bench/%.o: tests/bench/%.c | deps bench-deps
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) -Itests -c $< -o $@

$(BUILD)/bench/%: $(BUILD)/obj/bench/%.o $(TEST_SUPPORT_OBJ) $(BUILD)/libweathering.a
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) -o $@ $^ $(LIBS) $(BENCH_LIBS)

$(BUILD)/libweathering.a: $(LIB_OBJ)
	@mkdir -p $(dir $@)
	rm -f $@
	ar rcs $@ $^

$(BUILD)/weathering: $(CLI_OBJ) $(BUILD)/libweathering.a
	$(CC) $(ALL_CFLAGS) -o $@ $^ $(LIBS)

$(BUILD)/tests/%: $(BUILD)/obj/tests/%.o $(TEST_SUPPORT_OBJ) $(BUILD)/libweathering.a
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) -o $@ $^ $(LIBS)

# test_viewer checks the viewer's GL-free parts (its world, view and point
# filter) from the viewer's library.
$(BUILD)/tests/test_viewer: $(BUILD)/obj/tests/test_viewer.o $(TEST_SUPPORT_OBJ) \
    $(BUILD)/libweathering-viewer.a $(BUILD)/libweathering.a
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) -o $@ $^ $(LIBS)

# Tools for people and tests (each file's header says what it does): the CPU
# renderer of a TextureMap through an orthographic camera, built with the tests
# so that they can run it; preview_noise, how speckled a mask preview is.
$(BUILD)/tools/%: tests/tools/%.c $(BUILD)/libweathering.a | deps
	@mkdir -p $(dir $@)
	$(CC) $(filter-out -MMD -MP,$(ALL_CFLAGS)) -o $@ $^ $(LIBS)

# A test program whose source is gone (a test file renamed or split) is removed
# with its object before a run: run.sh runs every program in the folder.
define remove_stale_tests
	@for p in $(1)/tests/test_*; do n=$${p##*/}; \
	    [ ! -e "$$p" ] || [ -f tests/$$n.c ] || { echo "removing $$p: tests/$$n.c is gone"; \
	    rm -f "$$p" $(1)/obj/tests/$$n.o $(1)/obj/tests/$$n.d; }; done
endef

test: $(BUILD)/weathering $(VIEWER_BIN) $(TEST_BIN) $(BUILD)/tools/render_texture
	$(call remove_stale_tests,$(BUILD))
	WX_BUILD=$(BUILD) WX_TESTS=tests tests/run.sh $(BUILD)/tests

# make test-fast: the inner loop. Every test program, with the tests that take
# seconds (whole scene runs, marked SLOW() in tests/) counted as skipped: about
# 30 s on two cores. Both run the programs as many at a time as there are cores
# (tests/run.sh; WX_TEST_JOBS=1 runs them one by one).
test-fast: $(BUILD)/weathering $(VIEWER_BIN) $(TEST_BIN) $(BUILD)/tools/render_texture
	$(call remove_stale_tests,$(BUILD))
	WX_FAST=1 WX_BUILD=$(BUILD) WX_TESTS=tests tests/run.sh $(BUILD)/tests

# make test-blender: docs/mask.md's Blender recipe run for real (tests/blender/):
# two masks of building.obj are rendered back through Blender 3.4 (Cycles) and
# compared with mask.exr and mask.png; about 10 s. Installs Debian's blender like
# deps, after the build (so never while deps' apt-get runs). Outputs in
# $(BUILD)/blender-test/.
BLENDER_DEB_PACKAGES := blender
test-blender: $(BUILD)/weathering
	$(call install_missing,$(BLENDER_DEB_PACKAGES))
	tests/blender/run.sh $(BUILD)

# make test-cluster: `weathering tiles --slurm`'s job array and its merge run
# on a real one-node Slurm cluster (munged, slurmctld and slurmd started by
# tests/cluster/run.sh in a temp folder with tests/cluster/slurm.conf, stopped
# at its end); 10 to 15 s. Installs Debian's Slurm and MUNGE like deps, after
# the build. Outputs and the daemons' logs in $(BUILD)/cluster-test/.
CLUSTER_DEB_PACKAGES := munge slurmctld slurmd slurm-client
test-cluster: $(BUILD)/weathering
	$(call install_missing,$(CLUSTER_DEB_PACKAGES))
	tests/cluster/run.sh $(BUILD)

# Like deps, for the packages only the benchmarks need.
bench-deps:
	$(call install_missing,$(BENCH_DEB_PACKAGES))

# The benchmarks compiled but not run (a CI step: they are built against the
# library's headers, which the tests alone would let drift).
bench-build: $(BUILD)/weathering $(BENCH_BIN)

# Each benchmark prints its own table and appends its figures to $(BENCH_CSV);
# report.sh prints them as one table. A missed target is a MISSED row, never a
# stop (targets are checked here, never in make test); a benchmark that cannot
# run fails `make bench` after the others ran.
bench: $(BUILD)/weathering $(BENCH_BIN)
	@echo "bench,configuration,metric,value,unit,target,status" > $(BENCH_CSV); \
	failed=""; for b in $(BENCH_BIN); do echo "== $$b"; \
	    GALLIUM_DRIVER=llvmpipe WX_BUILD=$(BUILD) WX_BENCH_CSV=$(BENCH_CSV) $$b || failed="$$failed $$b"; \
	done; \
	sh tests/bench/report.sh $(BENCH_CSV); \
	if [ -n "$$failed" ]; then echo "benchmarks that could not run:$$failed"; exit 1; fi

# make gallery: every preset on every shipped model, one contact sheet
# (tests/tools/gallery.sh): docs/images/gallery.png, which the README shows,
# and its Spot row alone, docs/images/presets-spot.png.
# About 20 runs; GALLERY_RESOLUTION=N sets their --resolution (default 384).
gallery: $(BUILD)/weathering $(BUILD)/tools/render_texture $(BUILD)/tools/gallery
	sh tests/tools/gallery.sh $(BUILD) docs/images/gallery.png

# make previews: the other pictures of docs/images, from today's code
# (tests/tools/previews.sh: the shipped scenes and the house's derived masks;
# about 2 minutes on two cores).
previews: $(BUILD)/weathering $(BUILD)/tools/render_texture $(BUILD)/tools/exr_channel
	sh tests/tools/previews.sh $(BUILD)

# Bakes, simulates and gathers the default scene into out/<scene name>/ (mask.exr
# and its preview mask.png); SCENE=file.xml runs another scene.
run: $(BUILD)/weathering
	$(BUILD)/weathering run $(SCENE)

clean:
	rm -rf $(BUILD)

# --- MPI (docs/scale-out.md) -------------------------------------------------
# make mpi: the program built with Open MPI as $(MPI_BUILD)/weathering, for
# `mpirun -np N $(MPI_BUILD)/weathering run SCENE.xml`: the normal build's
# objects with core/dist.c compiled with -DWX_MPI (the only file that uses MPI),
# linked by Open MPI's mpicc. Installs Debian's Open MPI like deps.
MPI_BUILD ?= $(BUILD)-mpi
MPI_DEB_PACKAGES := libopenmpi-dev openmpi-bin
MPICC ?= mpicc
mpi-deps: | deps
	$(call install_missing,$(MPI_DEB_PACKAGES))

mpi: $(MPI_BUILD)/weathering

$(MPI_BUILD)/obj/core/dist.o: src/core/dist.c src/core/dist.h | deps mpi-deps
	@mkdir -p $(dir $@)
	$(MPICC) $(filter-out -MMD -MP,$(ALL_CFLAGS)) -DWX_MPI -c $< -o $@

$(MPI_BUILD)/weathering: $(CLI_OBJ) $(filter-out $(BUILD)/obj/core/dist.o,$(LIB_OBJ)) \
    $(MPI_BUILD)/obj/core/dist.o
	$(MPICC) $(filter-out -MMD -MP,$(ALL_CFLAGS)) -o $@ $^ $(LIBS)

# make test-mpi: tests/mpi/run.sh: small scenes run by the normal program and
# by mpirun -np 1, 2, 3 and 4 (more ranks than cores: --oversubscribe); every
# output file's SHA-256 must be the same. About 30 s on two cores.
test-mpi: $(BUILD)/weathering $(MPI_BUILD)/weathering
	tests/mpi/run.sh $(BUILD) $(MPI_BUILD)

# --- Reliability (docs/reliability.md) ---------------------------------------
# make sanitize: the whole suite built with AddressSanitizer and UBSan in its own
# folder ($(SAN_BUILD)); only the known Mesa leak is suppressed (tests/sanitize/).
SAN_BUILD ?= $(BUILD)-san
# float-cast-overflow is not part of 'undefined' in gcc: a float too large for
# the integer it becomes (a UV of 1e30 as a texel column) stops the test too.
SAN_CFLAGS := -O1 -g -fno-omit-frame-pointer -fsanitize=address,undefined,float-cast-overflow \
    -fno-sanitize-recover=all
# tests/sanitize/bin/xvfb-run keeps Mesa's GLX driver loaded in the viewer to the
# end, so that LeakSanitizer still sees the driver's globals at exit.
SAN_ENV := ASAN_OPTIONS=detect_leaks=1:strict_string_checks=1:check_initialization_order=1 \
    LSAN_OPTIONS=suppressions=$(CURDIR)/tests/sanitize/lsan.supp:print_suppressions=0 \
    UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 PATH="$(CURDIR)/tests/sanitize/bin:$$PATH"
# The reliability targets need a few more Debian packages than the build.
sanitize fuzz valgrind: DEB_PACKAGES += clang libclang-rt-dev valgrind
sanitize: | deps
	$(MAKE) --no-print-directory BUILD=$(SAN_BUILD) CFLAGS="$(SAN_CFLAGS)" \
	    $(SAN_BUILD)/weathering $(SAN_BUILD)/weathering-viewer $(SAN_BUILD)/tools/render_texture \
	    $(TEST_SRC:tests/%.c=$(SAN_BUILD)/tests/%)
	$(call remove_stale_tests,$(SAN_BUILD))
	$(SAN_ENV) WX_BUILD=$(SAN_BUILD) WX_TESTS=tests tests/run.sh $(SAN_BUILD)/tests

# make tsan: the tests of the threaded phases (simulate's chunk hand-off and
# ordered dirt exchange, the gather's rows, fixed and adaptive) built with ThreadSanitizer in
# $(TSAN_BUILD). Without function multiversioning: its load-time resolvers run
# before ThreadSanitizer is set up. The bake is left out: its threads are Mesa's (and
# the one that writes a run's camera files while the next renders; docs/reliability.md).
TSAN_BUILD ?= $(BUILD)-tsan
TSAN_CFLAGS := -O1 -g -fno-omit-frame-pointer -fsanitize=thread -DWX_NO_CLONES
TSAN_TESTS := test_simulate test_gather test_adaptive
tsan: | deps
	$(MAKE) --no-print-directory BUILD=$(TSAN_BUILD) CFLAGS="$(TSAN_CFLAGS)" \
	    $(TSAN_BUILD)/weathering $(TSAN_TESTS:%=$(TSAN_BUILD)/tests/%)
	@rm -rf $(TSAN_BUILD)/tsan-tests && mkdir -p $(TSAN_BUILD)/tsan-tests
	@for t in $(TSAN_TESTS); do ln -s ../tests/$$t $(TSAN_BUILD)/tsan-tests/$$t; done
	TSAN_OPTIONS=halt_on_error=1:second_deadlock_stack=1 WX_BUILD=$(TSAN_BUILD) \
	    WX_TESTS=tests tests/run.sh $(TSAN_BUILD)/tsan-tests

# make fuzz: libFuzzer targets (clang) in $(BUILD)/fuzz, seeded with the shipped
# scenes and maps and given their dictionary (tests/fuzz/TARGET.dict: the scene
# format's words, the EXR header's), each run for FUZZ_SECONDS. The library is rebuilt with clang
# and the fuzzer's instrumentation in $(BUILD)/fuzz/lib.
FUZZ_CC ?= clang
FUZZ_SECONDS ?= 30
FUZZ_CFLAGS := -O1 -g -fno-omit-frame-pointer -fsanitize=fuzzer-no-link,address,undefined \
    -fno-sanitize-recover=all -Wno-missing-field-initializers
FUZZ_TARGETS := $(patsubst tests/fuzz/%.c,$(BUILD)/fuzz/%,$(wildcard tests/fuzz/fuzz_*.c))
FUZZ_ENV := ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
    LSAN_OPTIONS=suppressions=$(CURDIR)/tests/sanitize/lsan.supp
$(BUILD)/fuzz/lib/libweathering.a: FORCE | deps
	$(MAKE) BUILD=$(BUILD)/fuzz/lib CC=$(FUZZ_CC) CFLAGS="$(FUZZ_CFLAGS)" $@

$(BUILD)/fuzz/%: tests/fuzz/%.c $(BUILD)/fuzz/lib/libweathering.a
	$(FUZZ_CC) $(WARN) $(DEFS) $(INCLUDES) $(FUZZ_CFLAGS) -fsanitize=fuzzer -o $@ $^ $(LIBS)

fuzz: $(FUZZ_TARGETS)
	@for t in $(FUZZ_TARGETS); do \
	    name=$$(basename $$t); corpus=$(BUILD)/fuzz/corpus/$$name; mkdir -p $$corpus; \
	    sh tests/fuzz/seed.sh $$name $$corpus || exit 1; \
	    echo "== $$name for $(FUZZ_SECONDS) s"; \
	    $(FUZZ_ENV) $$t -max_total_time=$(FUZZ_SECONDS) -timeout=10 -rss_limit_mb=4096 \
	        -dict=tests/fuzz/$$name.dict \
	        -malloc_limit_mb=4096 -print_final_stats=1 -artifact_prefix=$(BUILD)/fuzz/ \
	        $$corpus >$(BUILD)/fuzz/$$name.log 2>&1; status=$$?; \
	    grep -E '^(INFO: seed corpus|#[0-9]+ +DONE|stat::number_of_executed_units|Done )' \
	        $(BUILD)/fuzz/$$name.log; \
	    [ $$status -eq 0 ] || { tail -n 60 $(BUILD)/fuzz/$$name.log; exit 1; }; \
	done

# make valgrind: memcheck on two small scenes (maps given; maps baked), every phase;
# any error or definite leak fails.
VALGRIND := valgrind --error-exitcode=3 --leak-check=full --errors-for-leak-kinds=definite \
    --suppressions=tests/sanitize/valgrind.supp -q
valgrind: $(BUILD)/weathering | deps
	rm -rf $(BUILD)/valgrind
	GALLIUM_DRIVER=llvmpipe $(VALGRIND) $(BUILD)/weathering run tests/sanitize/valgrind.xml \
	    --out $(BUILD)/valgrind/maps -q --threads 2
	GALLIUM_DRIVER=llvmpipe $(VALGRIND) $(BUILD)/weathering run tests/sanitize/valgrind_bake.xml \
	    --out $(BUILD)/valgrind/bake -q --threads 2
	@echo "valgrind: no errors"

.PHONY: FORCE
FORCE:

# Object files of the tests and benchmarks are intermediates of their programs:
# keep them, so that a second `make test` relinks nothing it need not and the
# test count stays the last line of its output (make would delete them after).
.SECONDARY:

-include $(wildcard $(BUILD)/obj/*/*.d)
