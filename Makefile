# qdc - tetrahedral mesh optimization (library, CLI, daemon).
# `make run` and `make test` are the two commands a newcomer needs; both
# install missing Debian packages first (scripts/deps.sh, as root).

SANITIZER ?=
ifeq ($(SANITIZER),)
B := build/rel
SANFLAGS :=
else
B := build/san
SANFLAGS := -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined
endif

CC ?= cc
CXX ?= c++
OPTFLAGS ?= -O2 -g
WARN := -Wall -Wextra -Wpedantic -Werror -Wshadow -Wstrict-prototypes
CPPFLAGS += -D_POSIX_C_SOURCE=200809L -Ilib -I/usr/include/suitesparse
CFLAGS += -std=c11 $(OPTFLAGS) $(WARN) $(SANFLAGS) -fopenmp
CXXFLAGS += -std=c++11 $(OPTFLAGS) -Wall -Wextra -Werror $(SANFLAGS)
LDFLAGS += $(SANFLAGS) -fopenmp

LIB_C := $(wildcard lib/*.c)
LIB_CXX := $(wildcard lib/*.cpp)
LIB_OBJ := $(LIB_C:%.c=$(B)/%.o) $(LIB_CXX:%.cpp=$(B)/%.o)
LIB_LIBS := -lcholmod -lm
ifneq ($(LIB_CXX),)
LIB_LIBS += -ltet -lstdc++
endif

SRV_C := $(wildcard server/*.c)
SRV_OBJ := $(SRV_C:%.c=$(B)/%.o)
SRV_LIBS := -lmicrohttpd -ljansson -lsqlite3 -lpthread

CLI_C := $(wildcard clients/qdc/*.c)
CLI_OBJ := $(CLI_C:%.c=$(B)/%.o)
CLI_LIBS := -lcurl

UNIT_C := $(wildcard tests/unit/test_*.c)
UNIT_BIN := $(UNIT_C:tests/unit/%.c=$(B)/tests/%)

PROGS := $(B)/qdc $(if $(SRV_C),$(B)/qdcd)

.PHONY: all deps test test-quick run bench clean fuzz format
all: $(B)/libqdc.a $(PROGS) $(UNIT_BIN)

deps:
	@scripts/deps.sh

$(B)/%.o: %.c
	@mkdir -p $(dir $@)
	$(CC) $(CPPFLAGS) $(CFLAGS) -MMD -MP -c $< -o $@

$(B)/%.o: %.cpp
	@mkdir -p $(dir $@)
	$(CXX) $(CPPFLAGS) $(CXXFLAGS) -MMD -MP -c $< -o $@

$(B)/libqdc.a: $(LIB_OBJ)
	@mkdir -p $(dir $@)
	rm -f $@ && ar rcs $@ $^

$(B)/qdc: $(CLI_OBJ) $(B)/libqdc.a
	$(CC) $(LDFLAGS) -o $@ $(CLI_OBJ) $(B)/libqdc.a $(CLI_LIBS) $(LIB_LIBS)

$(B)/qdcd: $(SRV_OBJ) $(B)/libqdc.a
	$(CC) $(LDFLAGS) -o $@ $(SRV_OBJ) $(B)/libqdc.a $(SRV_LIBS) $(LIB_LIBS)

$(B)/tests/%: tests/unit/%.c tests/unit/testlib.h $(B)/libqdc.a
	@mkdir -p $(dir $@)
	$(CC) $(CPPFLAGS) -Itests/unit $(CFLAGS) -o $@ $< $(B)/libqdc.a $(LIB_LIBS) $(LDFLAGS)

# The whole suite: release build, sanitizer build, unit + end-to-end + daemon tests.
# The last line is "N passed, N failed".
test: deps
	$(MAKE) all
	$(MAKE) SANITIZER=1 all
	@tests/run.sh

# Unit tests of the release build only (seconds).
test-quick: all
	@QDC_QUICK=1 tests/run.sh

run: deps
	$(MAKE) all
	@scripts/run.sh

bench: deps
	$(MAKE) all
	@bench/run.sh

clean:
	rm -rf build

format:
	clang-format -i lib/*.c lib/*.h server/*.c server/*.h clients/qdc/*.c tests/unit/*.c

-include $(shell find build -name '*.d' 2>/dev/null)
