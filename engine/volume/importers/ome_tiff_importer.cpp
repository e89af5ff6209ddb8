#include "volume/importers/ome_tiff_importer.h"

#include <algorithm>
#include <cstring>
#include <optional>
#include <filesystem>
#include <fstream>
#include <map>
#include <pugixml.hpp>
#include <sstream>

#include "volume/channel_display.h"
#include "volume/importers/tiff_planes.h"
#include "core/checked_math.h"
#include "volume/importers/import_limits.h"
#include "volume/importers/tiff_reader.h"
#include "volume/importers/units.h"

namespace vxr {
namespace {

namespace fs = std::filesystem;

// Element name without a namespace prefix ("ome:Pixels" -> "Pixels").
std::string_view local_name(const pugi::xml_node& n) {
  std::string_view s = n.name();
  const size_t colon = s.find(':');
  return colon == std::string_view::npos ? s : s.substr(colon + 1);
}

pugi::xml_node child(const pugi::xml_node& parent, std::string_view name) {
  for (pugi::xml_node c : parent.children())
    if (c.type() == pugi::node_element && local_name(c) == name) return c;
  return {};
}

std::vector<pugi::xml_node> children(const pugi::xml_node& parent, std::string_view name) {
  std::vector<pugi::xml_node> out;
  for (pugi::xml_node c : parent.children())
    if (c.type() == pugi::node_element && local_name(c) == name) out.push_back(c);
  return out;
}

// Loads the OME-XML text of `path`: the first IFD's description of a TIFF, or the whole file.
Result<std::string> load_xml_text(const std::string& path) {
  if (tiff::has_tiff_magic(path)) {
    VXR_ASSIGN_OR_RETURN(std::unique_ptr<tiff::TiffFile> f, tiff::TiffFile::open(path));
    VXR_ASSIGN_OR_RETURN(tiff::PageInfo p, f->describe_current(0));
    if (!looks_like_ome_xml(p.description)) return invalid_argument(path + ": has no OME-XML in its first page");
    return p.description;
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) return not_found(path + ": cannot open");
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

Result<DType> ome_type(const std::string& where, std::string_view t) {
  if (t == "int8") return DType::kI8;
  if (t == "uint8" || t == "bit") return DType::kU8;
  if (t == "int16") return DType::kI16;
  if (t == "uint16") return DType::kU16;
  if (t == "int32") return DType::kI32;
  if (t == "uint32") return DType::kU32;
  if (t == "float" || t == "double") return DType::kF32;
  return unsupported(where + ": OME pixel type '" + std::string(t) + "' is not supported");
}

struct TiffDataRef {
  std::string file;
  uint32_t ifd = 0;
};

}  // namespace

// Channel@Name and Channel@Color of each channel, in channel order; empty
// when no Channel element states either (or the elements do not match SizeC).
std::vector<ChannelDisplay> ome_channel_display(const pugi::xml_node& pixels, uint32_t channels) {
  const std::vector<pugi::xml_node> elements = children(pixels, "Channel");
  if (elements.size() != channels) return {};
  std::vector<ChannelDisplay> out(channels);
  bool any = false;
  for (uint32_t c = 0; c < channels; ++c) {
    out[c].name = clean_channel_name(elements[c].attribute("Name").as_string());
    if (const pugi::xml_attribute color = elements[c].attribute("Color")) out[c].color = color_from_ome_int(color.as_string());
    any = any || !out[c].empty();
  }
  return any ? out : std::vector<ChannelDisplay>{};
}

bool looks_like_ome_xml(std::string_view d) {
  if (d.empty() || d.find('<') == std::string_view::npos) return false;
  return d.find("<OME") != std::string_view::npos || d.find(":OME ") != std::string_view::npos ||
         d.find(":OME>") != std::string_view::npos;
}

Result<std::unique_ptr<SlabSource>> open_ome_tiff_import(const std::string& path) {
  std::vector<std::string> warnings;
  std::string xml_path = path;  // the file whose XML describes the dataset
  VXR_ASSIGN_OR_RETURN(std::string text, load_xml_text(path));
  pugi::xml_document doc;
  pugi::xml_node ome;
  for (int hop = 0;; ++hop) {
    const pugi::xml_parse_result parsed = doc.load_buffer(text.data(), text.size());
    if (!parsed) return corrupt(xml_path + ": OME-XML does not parse (" + parsed.description() + ")");
    ome = {};
    for (pugi::xml_node n : doc.children())
      if (n.type() == pugi::node_element && local_name(n) == "OME") ome = n;
    if (!ome) return corrupt(xml_path + ": XML has no OME root element");
    const pugi::xml_node binary_only = child(ome, "BinaryOnly");
    if (!binary_only) break;
    const std::string meta = binary_only.attribute("MetadataFile").as_string();
    if (meta.empty() || hop > 2) return corrupt(xml_path + ": OME-XML BinaryOnly stub names no MetadataFile");
    const std::string next = (fs::path(xml_path).parent_path() / meta).string();
    if (!fs::exists(next))
      return not_found(next + ": missing (named as MetadataFile by " + xml_path + "); it holds the dataset's metadata");
    xml_path = next;
    VXR_ASSIGN_OR_RETURN(text, load_xml_text(xml_path));
  }
  const fs::path dir = fs::path(xml_path).parent_path();
  const bool xml_in_tiff = tiff::has_tiff_magic(xml_path);

  const std::vector<pugi::xml_node> images = children(ome, "Image");
  if (images.empty()) return corrupt(xml_path + ": OME-XML has no Image element");
  if (images.size() > 1)
    warnings.push_back(xml_path + ": holds " + std::to_string(images.size()) + " images (series); imported the first");
  const pugi::xml_node pixels = child(images[0], "Pixels");
  if (!pixels) return corrupt(xml_path + ": OME-XML Image has no Pixels element");

  const uint64_t sx = pixels.attribute("SizeX").as_ullong(), sy = pixels.attribute("SizeY").as_ullong();
  const uint32_t sz = pixels.attribute("SizeZ").as_uint(1), sc = pixels.attribute("SizeC").as_uint(1),
                 st = pixels.attribute("SizeT").as_uint(1);
  if (!sx || !sy || !sz || !sc || !st || sx > (1u << 31) || sy > (1u << 31))
    return corrupt(xml_path + ": OME-XML Pixels has missing or absurd sizes");
  std::string order = pixels.attribute("DimensionOrder").as_string("XYZCT");
  if (order.size() != 5 || order.substr(0, 2) != "XY" || order.find('Z') == std::string::npos ||
      order.find('C') == std::string::npos || order.find('T') == std::string::npos)
    return corrupt(xml_path + ": OME-XML DimensionOrder '" + order + "' is not a permutation of XY + ZCT");
  VXR_ASSIGN_OR_RETURN(DType dtype, ome_type(xml_path, pixels.attribute("Type").as_string()));

  // Samples per pixel from the first Channel; RGB planes hold 3 of the SizeC channels.
  uint32_t spp = 1;
  if (pugi::xml_node ch = child(pixels, "Channel")) spp = std::max(1u, ch.attribute("SamplesPerPixel").as_uint(1));
  if (sc % spp) spp = 1;
  const uint32_t plane_channels = sc / spp;
  // SizeZ x SizeC x SizeT can wrap 64 bits; and every plane costs a mapping
  // entry (~64 bytes) before any pixel is read, so the count must fit the budget.
  const auto counted = checked_product({sz, plane_channels, st});
  if (!counted || *counted > (1u << 26))
    return corrupt(xml_path + ": OME-XML describes an absurd number of planes (SizeZ " + std::to_string(sz) +
                   " x SizeC " + std::to_string(sc) + " x SizeT " + std::to_string(st) + ")");
  const uint64_t nplanes = *counted;
  if (nplanes * 64 > import_memory_budget() / 4)
    return out_of_range(xml_path + ": OME-XML describes " + std::to_string(nplanes) +
                        " planes, too many to map within the import memory budget; raise --memory");
  // Plane index <-> (z, c, t) following DimensionOrder (its 3rd letter varies fastest).
  auto size_of = [&](char d) -> uint64_t { return d == 'Z' ? sz : d == 'C' ? plane_channels : st; };
  auto plane_index = [&](uint64_t z, uint64_t c, uint64_t t) {
    uint64_t idx = 0, mult = 1;
    for (int i = 2; i < 5; ++i) {
      const char d = order[i];
      idx += (d == 'Z' ? z : d == 'C' ? c : t) * mult;
      mult *= size_of(d);
    }
    return idx;
  };

  // TiffData -> per-plane (file, IFD).
  std::vector<std::optional<TiffDataRef>> refs(nplanes);
  const std::vector<pugi::xml_node> tds = children(pixels, "TiffData");
  if (tds.empty()) {
    if (!xml_in_tiff) return corrupt(xml_path + ": OME-XML has no TiffData, so no plane has a file");
    for (uint64_t p = 0; p < nplanes; ++p) refs[p] = TiffDataRef{xml_path, uint32_t(p)};
  }
  for (const pugi::xml_node& td : tds) {
    std::string file = xml_path;
    if (pugi::xml_node uuid = child(td, "UUID")) {
      const std::string name = uuid.attribute("FileName").as_string();
      if (!name.empty()) file = (dir / name).string();
      else if (!xml_in_tiff) return corrupt(xml_path + ": a TiffData UUID has no FileName");
    } else if (!xml_in_tiff) {
      return corrupt(xml_path + ": a TiffData element names no file (UUID FileName)");
    }
    const bool has_ifd = !td.attribute("IFD").empty();
    const uint32_t ifd = td.attribute("IFD").as_uint(0);
    const uint64_t count =
        td.attribute("PlaneCount").empty() ? (has_ifd || tds.size() > 1 ? 1 : nplanes) : td.attribute("PlaneCount").as_ullong();
    const uint64_t first = plane_index(td.attribute("FirstZ").as_uint(0), td.attribute("FirstC").as_uint(0),
                                       td.attribute("FirstT").as_uint(0));
    for (uint64_t k = 0; k < count && first + k < nplanes; ++k) refs[first + k] = TiffDataRef{file, uint32_t(ifd + k)};
  }

  // Open every file once and describe its pages.
  TiffPlaneLayout layout;
  std::map<std::string, int32_t> file_index;
  std::unique_ptr<tiff::TiffFile> first_handle;
  uint64_t missing = 0;
  std::vector<TiffPlane> planes(nplanes);
  for (uint64_t p = 0; p < nplanes; ++p) {
    if (!refs[p]) {
      ++missing;
      continue;
    }
    auto it = file_index.find(refs[p]->file);
    if (it == file_index.end()) {
      if (!fs::exists(refs[p]->file))
        return not_found(refs[p]->file + ": missing; " + xml_path + " says it holds planes of the dataset");
      VXR_ASSIGN_OR_RETURN(std::unique_ptr<tiff::TiffFile> f, tiff::TiffFile::open(refs[p]->file));
      VXR_ASSIGN_OR_RETURN(std::vector<tiff::PageInfo> pages, f->scan_pages());
      it = file_index.emplace(refs[p]->file, int32_t(layout.files.size())).first;
      layout.files.push_back(refs[p]->file);
      layout.pages.push_back(std::move(pages));
      if (!first_handle) first_handle = std::move(f);
    }
    if (refs[p]->ifd >= layout.pages[it->second].size())
      return corrupt(refs[p]->file + ": has " + std::to_string(layout.pages[it->second].size()) +
                     " pages, but the OME-XML maps a plane to IFD " + std::to_string(refs[p]->ifd));
    planes[p] = TiffPlane{it->second, refs[p]->ifd};
  }
  if (missing == nplanes) return corrupt(xml_path + ": no plane of the dataset maps to a TIFF page");
  if (missing)
    warnings.push_back(xml_path + ": " + std::to_string(missing) + " of " + std::to_string(nplanes) +
                       " planes have no TiffData; they read as zeros");

  // Samples come from the pages themselves (an RGB page is 3 channels).
  const TiffPlane any = *std::find_if(planes.begin(), planes.end(), [](const TiffPlane& t) { return t.file >= 0; });
  const tiff::PageInfo& page = layout.pages[any.file][any.page];
  layout.samples = page.channels();
  if (dtype_bytes(page.dtype) != dtype_bytes(dtype))
    return corrupt(layout.files[any.file] + ": pages hold " + dtype_name(page.dtype) + " but the OME-XML says " +
                   pixels.attribute("Type").as_string());
  if (page.dtype == DType::kF32) dtype = DType::kF32;
  layout.info.dims = {sx, sy, sz};
  layout.info.dtype = dtype;
  layout.info.channels = plane_channels * layout.samples;
  layout.info.timepoints = st;
  layout.planes.resize(nplanes);
  for (uint32_t t = 0; t < st; ++t)
    for (uint32_t c = 0; c < plane_channels; ++c)
      for (uint32_t z = 0; z < sz; ++z) layout.plane(z, c, t) = planes[plane_index(z, c, t)];

  // Physical sizes: default unit µm; convert when the axes disagree.
  std::optional<double> size[3];
  std::optional<LengthUnit> unit[3];
  const char* axes[3] = {"X", "Y", "Z"};
  for (int a = 0; a < 3; ++a) {
    const pugi::xml_attribute v = pixels.attribute((std::string("PhysicalSize") + axes[a]).c_str());
    if (v.empty() || !(v.as_double() > 0)) continue;
    const pugi::xml_attribute u = pixels.attribute((std::string("PhysicalSize") + axes[a] + "Unit").c_str());
    unit[a] = u.empty() ? LengthUnit{"um", 1.0} : parse_length_unit(u.as_string());
    if (!unit[a]) {
      warnings.push_back(xml_path + ": PhysicalSize" + axes[a] + "Unit '" + u.as_string() + "' is not a length; ignored");
      continue;
    }
    size[a] = v.as_double();
  }
  VolumeInfo& info = layout.info;
  if (!size[0] && !size[1] && !size[2]) {
    info.unit = "px";
    info.voxel_size = {1, 1, 1};
  } else {
    bool same = true;
    std::string name;
    for (int a = 0; a < 3; ++a)
      if (size[a]) {
        if (name.empty()) name = unit[a]->name;
        same = same && unit[a]->name == name;
      }
    info.unit = same ? name : "um";
    double v[3];
    for (int a = 0; a < 3; ++a) v[a] = size[a] ? (same ? *size[a] : *size[a] * unit[a]->um) : 0;
    if (!size[0]) v[0] = size[1] ? v[1] : v[2];
    if (!size[1]) v[1] = v[0];
    if (!size[2]) {
      v[2] = v[0];
      if (sz > 1) warnings.push_back(xml_path + ": no PhysicalSizeZ; assumed the x pixel size");
    }
    info.voxel_size = {v[0], v[1], v[2]};
  }
  if (layout.samples == 1) info.channel_display = ome_channel_display(pixels, plane_channels);
  const std::string format =
      layout.files.size() > 1 ? "OME-TIFF (" + std::to_string(layout.files.size()) + " files)" : "OME-TIFF";
  return TiffPlaneSource::create(std::move(layout), format, std::move(warnings), std::move(first_handle));
}

}  // namespace vxr
