# Builds the libFuzzer targets straight from the sources, with clang and its own sanitizers
# (the CMake build may be GCC and unsanitised). run_fuzz.sh runs it as
#   make -f tests/fuzz/fuzz.mk SRC=<repository> WORK=<build dir>/tests/fuzz/work -j2
# Objects and dependency files stay in WORK, so a second run recompiles only what changed.
SRC ?= $(abspath $(dir $(lastword $(MAKEFILE_LIST)))/../..)
WORK ?= $(CURDIR)/fuzz-work
CXX := clang++
FLATC ?= flatc

SANITIZE := -fsanitize=address,undefined -fno-sanitize-recover=all
# -ffp-contract=off -fno-fast-math: the project's determinism flags (cmake/CsculptOptions.cmake).
CXXFLAGS := -std=c++20 -O1 -gline-tables-only -fno-omit-frame-pointer -ffp-contract=off \
  -fno-fast-math $(SANITIZE) -I$(SRC)/sdk/include -I$(SRC)/sdk/testkit/include -I$(SRC)/peer/include -I$(SRC)/capi/include \
  -I$(SRC)/tests/fuzz -isystem $(WORK)/generated -isystem /usr/include/eigen3 -MMD -MP

# The OpenMesh interop takes no bytes and needs OpenMesh's library: left out.
SDK_SOURCES := $(filter-out %/openmesh_interop.cpp,$(wildcard $(SRC)/sdk/src/*.cpp $(SRC)/sdk/src/simd/*.cpp))
SDK_OBJECTS := $(patsubst $(SRC)/sdk/src/%.cpp,$(WORK)/obj/sdk/%.o,$(SDK_SOURCES))
# The fixtures (built-in meshes) the fuzzers' seeds come from.
TESTKIT_OBJECTS := $(patsubst $(SRC)/sdk/testkit/src/%.cpp,$(WORK)/obj/testkit/%.o,$(wildcard $(SRC)/sdk/testkit/src/*.cpp))
# The C library also carries the peer sessions (ZeroMQ), which its entry points reference.
PEER_OBJECTS := $(patsubst $(SRC)/peer/src/%.cpp,$(WORK)/obj/peer/%.o,$(wildcard $(SRC)/peer/src/*.cpp))
CAPI_OBJECTS := $(patsubst $(SRC)/capi/src/%.cpp,$(WORK)/obj/capi/%.o,$(wildcard $(SRC)/capi/src/*.cpp))
ZMQ_LIBS := $(if $(PEER_OBJECTS),$(shell pkg-config --libs libzmq 2>/dev/null || echo -lzmq))
FUZZERS := fuzz_mesh_readers fuzz_wire_decode fuzz_capi_bytes
SCHEMAS := $(wildcard $(SRC)/sdk/schema/*.fbs $(SRC)/peer/schema/*.fbs)
GENERATED := $(patsubst %.fbs,$(WORK)/generated/%_generated.h,$(notdir $(SCHEMAS)))
# The project's version for capi_version.cpp's check (CMake passes it from project(VERSION)).
CAPI_VERSION := $(shell sed -n 's/^project.csculpt VERSION \([0-9]*\)\.\([0-9]*\)\.\([0-9]*\).*/-DCSCULPT_VERSION_MAJOR=\1 -DCSCULPT_VERSION_MINOR=\2 -DCSCULPT_VERSION_PATCH=\3/p' $(SRC)/CMakeLists.txt)
# Flags live here: a change to this file rebuilds everything.
THIS := $(lastword $(MAKEFILE_LIST))

all: $(addprefix $(WORK)/,$(FUZZERS))

$(WORK)/generated/%_generated.h: $(SRC)/sdk/schema/%.fbs
	$(FLATC) --cpp --scoped-enums -o $(WORK)/generated $<

$(WORK)/generated/%_generated.h: $(SRC)/peer/schema/%.fbs
	$(FLATC) --cpp --scoped-enums -o $(WORK)/generated $<

$(WORK)/obj/sdk/%.o: $(SRC)/sdk/src/%.cpp $(THIS) | $(GENERATED)
	@mkdir -p $(@D)
	$(CXX) $(CXXFLAGS) -fsanitize=fuzzer-no-link -c $< -o $@

$(WORK)/obj/testkit/%.o: $(SRC)/sdk/testkit/src/%.cpp $(THIS) | $(GENERATED)
	@mkdir -p $(@D)
	$(CXX) $(CXXFLAGS) -fsanitize=fuzzer-no-link -c $< -o $@

$(WORK)/obj/peer/%.o: $(SRC)/peer/src/%.cpp $(THIS) | $(GENERATED)
	@mkdir -p $(@D)
	$(CXX) $(CXXFLAGS) -fsanitize=fuzzer-no-link -c $< -o $@

$(WORK)/obj/capi/%.o: $(SRC)/capi/src/%.cpp $(THIS) | $(GENERATED)
	@mkdir -p $(@D)
	$(CXX) $(CXXFLAGS) $(CAPI_VERSION) -fsanitize=fuzzer-no-link -c $< -o $@

$(WORK)/obj/fuzz/%.o: $(SRC)/tests/fuzz/%.cpp $(THIS) | $(GENERATED)
	@mkdir -p $(@D)
	$(CXX) $(CXXFLAGS) -fsanitize=fuzzer -c $< -o $@

$(WORK)/obj/libsdk.a: $(SDK_OBJECTS) $(TESTKIT_OBJECTS)
	rm -f $@
	ar rcs $@ $^

$(WORK)/fuzz_capi_bytes: $(WORK)/obj/fuzz/fuzz_capi_bytes.o $(CAPI_OBJECTS) \
    $(PEER_OBJECTS) $(WORK)/obj/libsdk.a
	$(CXX) $(SANITIZE) -fsanitize=fuzzer $^ -o $@ -pthread $(ZMQ_LIBS)

$(WORK)/fuzz_%: $(WORK)/obj/fuzz/fuzz_%.o $(WORK)/obj/libsdk.a
	$(CXX) $(SANITIZE) -fsanitize=fuzzer $^ -o $@ -pthread

-include $(wildcard $(WORK)/obj/*/*.d)

.PHONY: all
.DELETE_ON_ERROR:
# Keep the fuzzers' own objects (make would delete them as intermediates of a pattern chain).
.SECONDARY:
