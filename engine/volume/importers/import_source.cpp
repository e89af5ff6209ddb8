#include "volume/importers/import_source.h"

#include <filesystem>

#include "volume/importers/raw_importer.h"

namespace vxr {
namespace {

std::string extension_lower(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}


// Wraps a source to override metadata with what the user said.
class HintedSource final : public SlabSource {
 public:
  HintedSource(std::unique_ptr<SlabSource> inner, const ImportHints& hints) : inner_(std::move(inner)) {
    info_ = inner_->info();
    if (hints.voxel_size) info_.voxel_size = *hints.voxel_size;
    if (hints.unit) info_.unit = *hints.unit;
  }
  const VolumeInfo& info() const override { return info_; }
  Status read_region(uint32_t c, uint32_t t, const Box3& box, std::span<uint8_t> dst) override {
    return inner_->read_region(c, t, box, dst);
  }
  std::vector<std::string> warnings() const override { return inner_->warnings(); }
  std::string format_name() const override { return inner_->format_name(); }

 private:
  std::unique_ptr<SlabSource> inner_;
  VolumeInfo info_;
};

}  // namespace

Result<std::unique_ptr<SlabSource>> open_import_source(const std::vector<std::string>& inputs,
                                                       const ImportHints& hints) {
  if (inputs.empty()) return invalid_argument("no input files given");
  const std::string& first = inputs.front();
  Result<std::unique_ptr<SlabSource>> source = unsupported(first + ": unrecognised input format");
  if (inputs.size() == 1 && extension_lower(first) == ".json") {
    source = open_raw_import(first);
  }
  if (!source) return source.status();
  if (!hints.voxel_size && !hints.unit) return source;
  return std::unique_ptr<SlabSource>(new HintedSource(std::move(source).value(), hints));
}

}  // namespace vxr
