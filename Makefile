# qdc - tetrahedral mesh optimization (library, CLI, daemon).
# `make run` and `make test` are the two commands a newcomer needs; both
# install missing Debian packages first (scripts/deps.sh, as root).

SANITIZER ?=
FAULT ?=
ifeq ($(SANITIZER),)
B := build/rel
SANFLAGS :=
else
B := build/san
SANFLAGS := -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined
endif
ifneq ($(TSAN),)
# ThreadSanitizer: qdcd's own threads (HTTP, intake, workers, poll timer)
B := build/tsan
SANFLAGS := -fsanitize=thread -fno-omit-frame-pointer
OPTFLAGS := -O1 -g
endif
ifneq ($(FAULT),)
# allocation-failure injection (lib/core/base.h qdc_fault_set) under the sanitizers
B := build/fault
SANFLAGS := -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined
CPPFLAGS += -DQDC_FAULT_INJECTION
endif

CC ?= cc
CXX ?= c++
OPTFLAGS ?= -O2 -g
WARN := -Wall -Wextra -Wpedantic -Werror -Wshadow -Wstrict-prototypes
CPPFLAGS += -D_POSIX_C_SOURCE=200809L -Ilib -Icommon -I/usr/include/suitesparse -I/usr/include/postgresql
# -fno-math-errno: sqrt and the like as single instructions, without the
# errno branch (the same results; lib/ sets no errno of its own)
CFLAGS += -std=c11 $(OPTFLAGS) $(WARN) $(SANFLAGS) -fopenmp -fno-math-errno
CXXFLAGS += -std=c++11 $(OPTFLAGS) -Wall -Wextra -Werror $(SANFLAGS)
LDFLAGS += $(SANFLAGS) -fopenmp

LIB_C := $(wildcard lib/*/*.c)
LIB_CXX := $(wildcard lib/*/*.cpp)
LIB_OBJ := $(LIB_C:%.c=$(B)/%.o) $(LIB_CXX:%.cpp=$(B)/%.o)
LIB_LIBS := -lcholmod -lz -lm
ifneq ($(LIB_CXX),)
LIB_LIBS += -ltet -lstdc++
endif

SRV_C := $(wildcard server/*.c) common/procenv.c
# The web console (web/) is compiled into qdcd: scripts/embed.sh turns its files
# into byte arrays (plain files, no build step of their own).
WEB_FILES := $(sort $(wildcard web/*.html web/*.js web/*.css web/*.svg))
SRV_OBJ := $(SRV_C:%.c=$(B)/%.o) $(if $(SRV_C),$(B)/gen/web_assets.o)
SRV_LIBS := -lmicrohttpd -ljansson -lsqlite3 -lpq -lpthread

CLI_C := $(wildcard clients/qdc/*.c) common/procenv.c
CLI_OBJ := $(CLI_C:%.c=$(B)/%.o)
CLI_LIBS := -lcurl

UNIT_C := $(wildcard tests/unit/test_*.c)
UNIT_BIN := $(UNIT_C:tests/unit/%.c=$(B)/tests/%)

# Programs that use the library as an outside program would: qdc.h alone
# (tests/e2e/example.sh runs them).
EX_C := $(wildcard examples/*.c)
EX_BIN := $(EX_C:%.c=$(B)/%)

# qdc-h5: HDF5 (MED files) in a program of its own, which the qdc command runs
# as a child (libqdc never calls HDF5); built when libhdf5-dev is there.
H5_CFLAGS := $(shell pkg-config --cflags hdf5 2>/dev/null)
H5_LIBS := $(shell pkg-config --libs hdf5 2>/dev/null)
H5_PROG := $(if $(H5_LIBS),$(B)/qdc-h5)

PROGS := $(B)/qdc $(if $(SRV_C),$(B)/qdcd) $(H5_PROG)

.PHONY: all hooks deps test test-quick test-container test-faults test-load run bench clean fuzz fuzz-run format format-check fault
all: $(B)/libqdc.a $(PROGS) $(UNIT_BIN) $(EX_BIN) hooks

# The commit-msg hook for contributors (scripts/commit-msg: subjects of at
# most 72 characters), copied into git's hooks directory when this tree is
# the top of a git checkout (a clone or a worktree) whose hooks directory
# exists (git makes it in every clone). Skipped without .git (a tarball, a CI
# export), with QDC_NO_HOOKS=1, or when another commit-msg hook is there.
hooks:
	@[ -z "$(QDC_NO_HOOKS)" ] || exit 0; \
	top=$$(git rev-parse --show-toplevel 2>/dev/null) || exit 0; \
	[ "$$top" -ef . ] || exit 0; \
	h=$$(git rev-parse --git-path hooks 2>/dev/null) || exit 0; \
	[ -d "$$h" ] || exit 0; \
	if [ ! -e "$$h/commit-msg" ] || grep -q '^# scripts/commit-msg' "$$h/commit-msg"; then \
	    cmp -s scripts/commit-msg "$$h/commit-msg" || \
	    { cp scripts/commit-msg "$$h/commit-msg" && chmod +x "$$h/commit-msg" && \
	      echo "installed the commit-msg hook in $$h"; }; \
	fi

deps:
	@scripts/deps.sh

$(B)/%.o: %.c
	@mkdir -p $(dir $@)
	$(CC) $(CPPFLAGS) $(CFLAGS) -MMD -MP -c $< -o $@

$(B)/%.o: %.cpp
	@mkdir -p $(dir $@)
	$(CXX) $(CPPFLAGS) $(CXXFLAGS) -MMD -MP -c $< -o $@

$(B)/gen/web_assets.c: scripts/embed.sh $(WEB_FILES) web
	@mkdir -p $(dir $@)
	sh scripts/embed.sh $@ $(WEB_FILES)

$(B)/gen/web_assets.o: $(B)/gen/web_assets.c server/ui.h
	$(CC) $(CPPFLAGS) -Iserver $(CFLAGS) -c $< -o $@

$(B)/libqdc.a: $(LIB_OBJ)
	@mkdir -p $(dir $@)
	rm -f $@ && ar rcs $@ $^

$(B)/qdc: $(CLI_OBJ) $(B)/libqdc.a
	$(CC) $(LDFLAGS) -o $@ $(CLI_OBJ) $(B)/libqdc.a $(CLI_LIBS) $(LIB_LIBS)

$(B)/qdc-h5: clients/qdc-h5/qdc-h5.c
	@mkdir -p $(dir $@)
	$(CC) $(H5_CFLAGS) $(CFLAGS) -o $@ $< $(H5_LIBS) $(LDFLAGS)

$(B)/qdcd: $(SRV_OBJ) $(B)/libqdc.a
	$(CC) $(LDFLAGS) -o $@ $(SRV_OBJ) $(B)/libqdc.a $(SRV_LIBS) $(LIB_LIBS)

$(B)/tests/%: tests/unit/%.c $(wildcard tests/unit/*.h) $(B)/libqdc.a
	@mkdir -p $(dir $@)
	$(CC) $(CPPFLAGS) -Itests/unit $(CFLAGS) -o $@ $< $(B)/libqdc.a $(LIB_LIBS) $(LDFLAGS)

$(B)/examples/%: examples/%.c lib/qdc.h $(B)/libqdc.a
	@mkdir -p $(dir $@)
	$(CC) $(CPPFLAGS) $(CFLAGS) -o $@ $< $(B)/libqdc.a $(LIB_LIBS) $(LDFLAGS)

# The daemon's pure parsers and router, linked alone (no libmicrohttpd).
HTTP_PURE_OBJ := $(B)/server/route.o $(B)/server/parse.o $(B)/server/problem.o $(B)/server/util.o
$(B)/tests/test_http: tests/unit/test_http.c tests/unit/testlib.h tests/unit/testio.h tests/fuzz/fuzz_http.c $(HTTP_PURE_OBJ) $(B)/libqdc.a
	@mkdir -p $(dir $@)
	$(CC) $(CPPFLAGS) -Itests/unit -Iserver $(CFLAGS) -o $@ $< $(HTTP_PURE_OBJ) $(B)/libqdc.a \
	    $(LIB_LIBS) $(LDFLAGS)

# The multipart parser, linked alone.
$(B)/tests/test_multipart: tests/unit/test_multipart.c tests/unit/testlib.h tests/unit/testio.h tests/fuzz/fuzz_multipart.c $(B)/server/multipart.o $(B)/libqdc.a
	@mkdir -p $(dir $@)
	$(CC) $(CPPFLAGS) -Itests/unit -Iserver $(CFLAGS) -o $@ $< $(B)/server/multipart.o \
	    $(B)/libqdc.a $(LIB_LIBS) $(LDFLAGS)

# The whole suite: release build, sanitizer build, unit + end-to-end + daemon tests,
# two suites at a time (tests/run.sh; QDC_TEST_JOBS=1 for one at a time).
# The last line is "N passed, N failed".
test: deps
	$(MAKE) -j$$(nproc) all
	$(MAKE) -j$$(nproc) SANITIZER=1 all
	$(MAKE) -j$$(nproc) TSAN=1 build/tsan/qdcd
	@tests/run.sh

# Unit tests of the release build only (seconds).
test-quick: all
	@QDC_QUICK=1 tests/run.sh

# The daemon's fault suite alone (also part of make test).
test-faults: deps
	$(MAKE) -j$$(nproc) all
	@for t in tests/faults/*.sh; do sh "$$t"; done

# The mixed-traffic load test for 10 minutes (make test runs it for 30 s).
test-load: deps
	$(MAKE) -j$$(nproc) all
	QDC_LOAD_SECONDS=600 sh tests/faults/load.sh

# The images built and run by a container engine (Podman here; skipped without
# one): one qdcd on a volume, and compose.yaml's 3 replicas on PostgreSQL.
test-container: deps
	$(MAKE) -j$$(nproc) all
	@for t in tests/container/*.sh; do sh "$$t"; done

# Every allocation of the library failing in turn: clean errors, no leaks.
# Then transient I/O faults in the daemon (short writes, ENOSPC, EIO, fsync
# failures on uploads, the job store, results and conversions).
fault:
	$(MAKE) FAULT=1 $(UNIT_BIN:build/rel/%=build/fault/%)
	@for t in build/fault/tests/test_*; do ASAN_OPTIONS=detect_leaks=1 $$t || exit 1; done
	$(MAKE) -j$$(nproc) all
	@out=$$(sh tests/faults/io.sh); echo "$$out"; ! echo "$$out" | grep -q '^FAIL'

# Builds only what it serves (in parallel), so a fresh clone answers quickly.
run: deps
	$(MAKE) -j$$(nproc) $(B)/qdcd $(B)/qdc
	@scripts/run.sh

bench: deps
	$(MAKE) all
	@bench/run.sh

clean:
	rm -rf build

FORMAT_SRC = $(wildcard lib/*.h lib/*/*.c lib/*/*.h lib/*/*.cpp server/*.c server/*.h clients/qdc/*.c \
              common/*.c common/*.h \
              clients/qdc/*.h tests/unit/*.c tests/unit/*.h tests/fuzz/*.c tests/fuzz/*.h \
              examples/*.c)
format:
	clang-format -i $(FORMAT_SRC)

# No layout difference (also run by make test: tests/house/format.sh).
format-check:
	clang-format --dry-run -Werror $(FORMAT_SRC)

-include $(shell find build -name '*.d' 2>/dev/null)

# libFuzzer targets (clang-14 and its libFuzzer runtime, scripts/deps.sh): each
# tests/fuzz/fuzz_NAME.c is built with the library's io/ layer and run FUZZ_SECONDS on
# its seeds (tests/fuzz/seeds/NAME); crashes land in tests/fuzz/crashes/NAME, which
# `make test` replays (unit tests). FUZZ=name runs one target. A target that crashes
# fails the run. CI runs `make fuzz FUZZ_SECONDS=20` (.ci/run).
FUZZ_SECONDS ?= 60
FUZZ_CC ?= $(shell command -v clang-14 2>/dev/null || echo clang)
FUZZ_LIB := lib/core/base.c lib/core/mesh.c lib/core/pdata.c $(wildcard lib/io/*.c) server/parse.c server/route.c \
            server/multipart.c
FUZZ_SRC := $(if $(FUZZ),tests/fuzz/fuzz_$(FUZZ).c,$(wildcard tests/fuzz/fuzz_*.c))
FUZZ_FLAGS := -g -O1 -fno-sanitize-recover=undefined -fopenmp $(CPPFLAGS) -Iserver -MMD -MP
# the library is compiled once for every target (instrumented, not linked
# with the fuzzer's main), each target then only its own file
FUZZ_OBJ := $(patsubst %.c,build/fuzz/obj/%.o,$(FUZZ_LIB))
build/fuzz/obj/%.o: %.c
	@mkdir -p $(dir $@)
	$(FUZZ_CC) -fsanitize=fuzzer-no-link,address,undefined $(FUZZ_FLAGS) -c $< -o $@
fuzz: deps
	@$(MAKE) --no-print-directory fuzz-run
fuzz-run: $(FUZZ_OBJ)
	@mkdir -p build/fuzz
	@set -e; for src in $(FUZZ_SRC); do \
	    name=$$(basename $$src .c); name=$${name#fuzz_}; \
	    echo "# fuzz $$name ($(FUZZ_SECONDS) s)"; \
	    $(FUZZ_CC) -fsanitize=fuzzer,address,undefined $(FUZZ_FLAGS) $$src $(FUZZ_OBJ) \
	        -lz -lm -o build/fuzz/fuzz_$$name; \
	    mkdir -p build/fuzz/corpus/$$name tests/fuzz/crashes/$$name; \
	    OMP_NUM_THREADS=1 build/fuzz/fuzz_$$name -max_total_time=$(FUZZ_SECONDS) -max_len=8192 \
	        -artifact_prefix=tests/fuzz/crashes/$$name/ build/fuzz/corpus/$$name \
	        tests/fuzz/seeds/$$name; \
	    rmdir tests/fuzz/crashes/$$name 2>/dev/null || true; \
	done
