// Chunk payload decoding. Input: codec byte, dtype byte, edge byte (chunk
// edge 1 + b % 40), the 8-byte uniform value, then the stored payload.
#include <cstring>
#include <vector>

#include "fuzz_util.h"
#include "volume/chunk_codec.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 11) return 0;
  const auto codec = static_cast<vxr::vxc::Codec>(data[0] % 4);
  const auto dtype = static_cast<vxr::DType>(data[1] % (uint8_t(vxr::DType::kF32) + 1));
  const uint64_t edge = 1 + data[2] % 40;
  double value;
  std::memcpy(&value, data + 3, 8);
  std::vector<uint8_t> out(edge * edge * edge * vxr::dtype_bytes(dtype));
  const std::span<const uint8_t> stored(data + 11, size - 11);
  if (vxr::decode_payload(codec, dtype, {value, value}, stored, out)) {
    // What decodes must encode and decode back to the same voxels.
    const vxr::EncodedChunk enc = vxr::encode_chunk({}, dtype, out, codec);
    std::vector<uint8_t> again(out.size());
    if (!vxr::decode_payload(enc.codec, dtype, enc.stats, enc.stored, again) || again != out) __builtin_trap();
  }
  return 0;
}
