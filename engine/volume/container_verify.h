// Full integrity check of a .vxc file, for `vxr verify`.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace vxr {

struct VerifyReport {
  uint64_t chunks_checked = 0;     // chunk records whose checksums were computed
  std::vector<std::string> problems;  // one line each: the damaged part (named chunk, index, footer, header)
  bool ok() const { return problems.empty(); }
};

// Checks the header, the footer, the index (checksum, bounds, duplicates,
// completeness) and every chunk (record header against index entry, payload
// checksum, decoding). Keeps going after damage: with a damaged index the
// entries are still compared one by one with their records; with a damaged
// footer the chunk records are scanned in file order. Never throws or crashes
// on malformed input.
VerifyReport verify_container(const std::string& path);

}  // namespace vxr
