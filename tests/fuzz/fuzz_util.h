// Shared by the libFuzzer harnesses (tests/fuzz/fuzz_<name>.cpp): each one
// defines LLVMFuzzerTestOneInput, built either with -fsanitize=fuzzer (the
// `fuzz` preset) or with replay_main.cpp, which runs every file of a corpus
// folder through it (ctest fuzz_replay.<name> in the normal build).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "volume/slab_source.h"

namespace vxr::fuzz {

// Writes `size` bytes to `name` in a per-process scratch folder (importers
// read files, not memory) and returns the path; the file is rewritten on
// every call, so one input never sees another's leftovers.
std::string write_temp(const std::string& name, const uint8_t* data, size_t size);

// Reads what an import would: a corner box of every channel and timepoint
// (at most 4 and 2) at both ends of the volume, at most 64 x 64 x 2 voxels
// each, so the harness's own buffers stay small whatever the dims claim.
// Errors are the expected outcome for most inputs and are ignored.
void read_some(SlabSource& source);

}  // namespace vxr::fuzz

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);
