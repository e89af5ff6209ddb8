#include "volume/zarr/ome_zarr.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "volume/channel_display.h"
#include "volume/importers/units.h"

namespace vxr::zarr {
namespace {

using json = nlohmann::json;
namespace fs = std::filesystem;

Status bad(const std::string& what, const std::string& why) {
  return invalid_argument(what + ": " + why);
}

std::string join_key(const std::string& prefix, const std::string& key) {
  return prefix.empty() ? key : prefix + "/" + key;
}

// The attributes of the group at `prefix`: v3 zarr.json "attributes" (with
// OME 0.5 metadata under "ome", lifted here), or v2 .zattrs. `what` receives
// the file they came from; `is_array` is set when the node is an array.
struct GroupAttrs {
  json attrs = json::object();
  std::string what;
  std::string ome_version;  // from attributes.ome.version (0.5)
  bool is_array = false;
  bool found = false;
};

// omero.channels[c]: label, color ("RRGGBB"), window {start, end}. Display
// hints only: a field of the wrong type is skipped, never an error. Empty
// when nothing usable is stated or the list does not match the channel count.
std::vector<ChannelDisplay> omero_channel_display(const json& attrs, uint32_t channels,
                                                  std::vector<std::string>& warnings) {
  if (!attrs.contains("omero") || !attrs.at("omero").is_object()) return {};
  const json& omero = attrs.at("omero");
  if (!omero.contains("channels") || !omero.at("channels").is_array()) return {};
  const json& list = omero.at("channels");
  if (list.size() != channels) {
    warnings.push_back("'omero'.'channels' lists " + std::to_string(list.size()) + " channels, the image has " +
                       std::to_string(channels) + "; channel names and colours ignored");
    return {};
  }
  std::vector<ChannelDisplay> out(channels);
  bool any = false;
  for (uint32_t c = 0; c < channels; ++c) {
    const json& ch = list[c];
    if (!ch.is_object()) continue;
    ChannelDisplay& d = out[c];
    if (ch.contains("label") && ch.at("label").is_string()) d.name = clean_channel_name(ch.at("label").get<std::string>());
    if (ch.contains("color") && ch.at("color").is_string()) d.color = color_from_hex(ch.at("color").get<std::string>());
    if (ch.contains("window") && ch.at("window").is_object()) {
      const json& w = ch.at("window");
      if (w.contains("start") && w.contains("end") && w.at("start").is_number() && w.at("end").is_number()) {
        const double lo = w.at("start").get<double>(), hi = w.at("end").get<double>();
        if (std::isfinite(lo) && std::isfinite(hi) && hi > lo) d.window = std::array<double, 2>{lo, hi};
      }
    }
    any = any || !d.empty();
  }
  return any ? out : std::vector<ChannelDisplay>{};
}

Result<GroupAttrs> read_attrs(const ZarrStore& store, const std::string& prefix) {
  GroupAttrs g;
  auto parse = [&](const std::vector<uint8_t>& bytes, const std::string& what) -> Result<json> {
    try {
      return json::parse(bytes.begin(), bytes.end());
    } catch (const json::parse_error& e) {
      return bad(what, "not valid JSON (syntax error at byte " + std::to_string(e.byte) + ")");
    }
  };
  VXR_ASSIGN_OR_RETURN(auto v3, store.get(join_key(prefix, "zarr.json")));
  if (v3) {
    g.what = store.describe(join_key(prefix, "zarr.json"));
    VXR_ASSIGN_OR_RETURN(json j, parse(*v3, g.what));
    if (!j.is_object()) return bad(g.what, "must hold a JSON object");
    g.found = true;
    g.is_array = j.value("node_type", "") == "array";
    if (j.contains("attributes")) {
      if (!j.at("attributes").is_object()) return bad(g.what, "'attributes' must be an object");
      g.attrs = j.at("attributes");
      if (g.attrs.contains("ome")) {
        const json ome = g.attrs.at("ome");
        if (!ome.is_object()) return bad(g.what, "'attributes'.'ome' must be an object");
        if (ome.contains("version") && ome.at("version").is_string()) g.ome_version = ome.at("version");
        g.attrs = ome;
      }
    }
    return g;
  }
  VXR_ASSIGN_OR_RETURN(auto zattrs, store.get(join_key(prefix, ".zattrs")));
  VXR_ASSIGN_OR_RETURN(auto zarray, store.get(join_key(prefix, ".zarray")));
  VXR_ASSIGN_OR_RETURN(auto zgroup, store.get(join_key(prefix, ".zgroup")));
  g.found = zattrs || zarray || zgroup;
  g.is_array = zarray.has_value();
  g.what = store.describe(join_key(prefix, ".zattrs"));
  if (zattrs) {
    VXR_ASSIGN_OR_RETURN(g.attrs, parse(*zattrs, g.what));
    if (!g.attrs.is_object()) return bad(g.what, "must hold a JSON object");
  }
  return g;
}

enum class Role { kTime, kChannel, kSpace };

struct Axis {
  std::string name;
  Role role = Role::kSpace;
  std::string unit;
};

// Axes by rank when the metadata has none (OME 0.1/0.2, bare arrays).
std::vector<Axis> default_axes(size_t n) {
  static const char* names[] = {"t", "c", "z", "y", "x"};
  std::vector<Axis> out;
  for (size_t i = 5 - n; i < 5; ++i)
    out.push_back({names[i], i == 0 ? Role::kTime : i == 1 ? Role::kChannel : Role::kSpace, ""});
  return out;
}

Result<std::vector<Axis>> parse_axes(const json& ms, size_t ndim, const std::string& what) {
  const std::string where = "'multiscales'[0]: 'axes'";
  if (!ms.contains("axes")) return default_axes(ndim);
  const json& a = ms.at("axes");
  if (!a.is_array() || a.size() != ndim)
    return bad(what, where + " must be a list of " + std::to_string(ndim) + " axes (one per array dimension)");
  std::vector<Axis> out;
  for (size_t i = 0; i < a.size(); ++i) {
    Axis ax;
    std::string type;
    if (a[i].is_string()) {  // OME 0.3
      ax.name = a[i].get<std::string>();
    } else if (a[i].is_object() && a[i].contains("name") && a[i].at("name").is_string()) {
      ax.name = a[i].at("name").get<std::string>();
      if (a[i].contains("type") && a[i].at("type").is_string()) type = a[i].at("type").get<std::string>();
      if (a[i].contains("unit") && a[i].at("unit").is_string()) ax.unit = a[i].at("unit").get<std::string>();
    } else {
      return bad(what, where + "[" + std::to_string(i) + "] must be an object with a string 'name'");
    }
    if (type.empty())
      type = ax.name == "t"                                       ? "time"
             : ax.name == "c"                                     ? "channel"
             : ax.name == "x" || ax.name == "y" || ax.name == "z" ? "space"
                                                                  : "";
    ax.role = type == "space" ? Role::kSpace : type == "time" ? Role::kTime : Role::kChannel;
    out.push_back(ax);
  }
  return out;
}

// scale and translation of one coordinateTransformations list (identity when absent).
Status parse_transforms(const json& list, size_t ndim, const std::string& what, const std::string& where,
                        std::vector<double>& scale, std::vector<double>& translation, bool& has_scale) {
  if (!list.is_array()) return bad(what, where + " must be a list");
  for (size_t i = 0; i < list.size(); ++i) {
    const json& t = list[i];
    const std::string at = where + "[" + std::to_string(i) + "]";
    if (!t.is_object() || !t.contains("type") || !t.at("type").is_string())
      return bad(what, at + " must be an object with a string 'type'");
    const std::string type = t.at("type");
    if (type == "identity") continue;
    if (type != "scale" && type != "translation")
      return unsupported(what + ": " + at + ": transformation '" + type + "' is not read (scale, translation)");
    if (t.contains("path"))
      return unsupported(what + ": " + at + ": transformations stored in a separate array are not read");
    const json& v = t.contains(type) ? t.at(type) : json();
    if (!v.is_array() || v.size() != ndim)
      return bad(what, at + ": '" + type + "' must be a list of " + std::to_string(ndim) + " numbers");
    for (size_t k = 0; k < ndim; ++k) {
      if (!v[k].is_number())
        return bad(what, at + ": '" + type + "' must be a list of " + std::to_string(ndim) + " numbers");
      const double x = v[k].get<double>();
      if (type == "scale") {
        if (!(x > 0) || !std::isfinite(x)) return bad(what, at + ": 'scale' values must be positive");
        scale[k] *= x;
        translation[k] *= x;
        has_scale = true;
      } else {
        if (!std::isfinite(x)) return bad(what, at + ": 'translation' values must be finite");
        translation[k] += x;
      }
    }
  }
  return Status();
}

}  // namespace

bool looks_like_zarr(const std::string& path) {
  std::error_code ec;
  fs::path p(path);
  const std::string name = p.filename().string();
  if (name == "zarr.json" || name == ".zattrs" || name == ".zgroup" || name == ".zarray")
    return fs::is_regular_file(p, ec);
  if (!fs::is_directory(p, ec)) return false;
  for (const char* f : {"zarr.json", ".zattrs", ".zgroup", ".zarray"})
    if (fs::is_regular_file(p / f, ec)) return true;
  return false;
}

Result<std::unique_ptr<OmeZarrImage>> OmeZarrImage::open(const std::string& path, uint64_t cache_bytes) {
  // Every key is type-checked before use; this only turns a check we missed
  // into a message instead of an exception leaving the module.
  try {
    return open_checked(path, cache_bytes);
  } catch (const json::exception& e) {
    return invalid_argument(path + ": unexpected value in the OME-Zarr metadata (" + e.what() + ")");
  }
}

Result<std::unique_ptr<OmeZarrImage>> OmeZarrImage::open_checked(const std::string& path, uint64_t cache_bytes) {
  std::error_code ec;
  fs::path p(path);
  const std::string fname = p.filename().string();
  if (fname == "zarr.json" || fname == ".zattrs" || fname == ".zgroup" || fname == ".zarray") p = p.parent_path();
  std::string root = p.string();
  while (root.size() > 1 && root.back() == '/') root.pop_back();
  if (!fs::exists(root, ec)) return not_found(root + ": no such file or folder");
  if (!fs::is_directory(root, ec)) return invalid_argument(root + ": an OME-Zarr image is a folder, this is a file");
  auto store = std::make_shared<DirectoryStore>(root);
  std::unique_ptr<OmeZarrImage> img(new OmeZarrImage());
  img->root_ = root;

  std::string prefix;
  VXR_ASSIGN_OR_RETURN(GroupAttrs g, read_attrs(*store, prefix));
  if (!g.found)
    return invalid_argument(root + ": not a Zarr folder (no .zgroup, .zattrs or zarr.json); OME-Zarr images hold " +
                            "one of these at the top");
  if (!g.is_array && !g.attrs.contains("multiscales") && g.attrs.contains("bioformats2raw.layout")) {
    prefix = "0";  // bioformats2raw: the first image of the series
    VXR_ASSIGN_OR_RETURN(g, read_attrs(*store, prefix));
  }

  json ms;  // the multiscale, or null for a bare array
  if (!g.is_array) {
    if (!g.attrs.contains("multiscales"))
      return invalid_argument(g.what + ": no 'multiscales' key, so this is not an OME-Zarr image; open the image " +
                              "group inside it, or a Zarr array");
    const json& list = g.attrs.at("multiscales");
    if (!list.is_array() || list.empty() || !list[0].is_object())
      return bad(g.what, "'multiscales' must be a non-empty list of objects");
    if (list.size() > 1) img->warnings_.push_back("using the first of " + std::to_string(list.size()) + " multiscales");
    ms = list[0];
    img->version_ = !g.ome_version.empty() ? g.ome_version : ms.value("version", "");
    if (!ms.contains("datasets") || !ms.at("datasets").is_array() || ms.at("datasets").empty())
      return bad(g.what, "'multiscales'[0]: 'datasets' must be a non-empty list");
  }

  // Open the arrays.
  const uint64_t per_level = cache_bytes / std::max<size_t>(1, g.is_array ? 1 : ms.at("datasets").size());
  std::vector<std::string> paths;
  if (g.is_array) {
    paths.push_back(prefix);
  } else {
    const json& ds = ms.at("datasets");
    for (size_t i = 0; i < ds.size(); ++i) {
      if (!ds[i].is_object() || !ds[i].contains("path") || !ds[i].at("path").is_string() ||
          ds[i].at("path").get<std::string>().empty())
        return bad(g.what,
                   "'multiscales'[0]: 'datasets'[" + std::to_string(i) + "] must have a non-empty string 'path'");
      paths.push_back(join_key(prefix, ds[i].at("path").get<std::string>()));
    }
  }
  for (const std::string& dp : paths) {
    OmeLevel level;
    level.path = dp;
    VXR_ASSIGN_OR_RETURN(level.array, ZarrArray::open(store, dp, per_level));
    img->levels_.push_back(std::move(level));
  }
  const ArrayMeta& m0 = img->levels_[0].array->meta();
  const size_t ndim = m0.shape.size();
  for (size_t i = 1; i < img->levels_.size(); ++i) {
    const ArrayMeta& m = img->levels_[i].array->meta();
    if (m.shape.size() != ndim || m.dtype != m0.dtype)
      return bad(g.what, "'multiscales'[0]: dataset '" + img->levels_[i].path + "' has " +
                             std::to_string(m.shape.size()) + " dimensions of " + dtype_name(m.dtype) + ", level 0 " +
                             std::to_string(ndim) + " of " + dtype_name(m0.dtype) + "; levels must agree");
  }

  // Axes: roles and units.
  std::vector<Axis> axes;
  if (g.is_array) {
    if (ndim < 2 || ndim > 5) return bad(g.what, "a bare array must have 2..5 dimensions");
    axes = default_axes(ndim);
  } else {
    VXR_ASSIGN_OR_RETURN(axes, parse_axes(ms, ndim, g.what));
  }
  int spaces = 0;
  for (size_t i = 0; i < axes.size(); ++i) {
    const int a = static_cast<int>(i);
    if (axes[i].role == Role::kTime) {
      if (img->t_axis_ >= 0) return bad(g.what, "'multiscales'[0]: 'axes' has more than one time axis");
      img->t_axis_ = a;
    } else if (axes[i].role == Role::kChannel) {
      if (img->c_axis_ >= 0)
        return unsupported(g.what + ": 'multiscales'[0]: 'axes' has more than one channel-like axis ('" +
                           axes[img->c_axis_].name + "', '" + axes[i].name + "'); vxr reads [t][c][z]yx");
      img->c_axis_ = a;
    } else {
      ++spaces;
    }
  }
  if (spaces < 2 || spaces > 3)
    return bad(g.what, "'multiscales'[0]: 'axes' must have 2 or 3 space axes, it has " + std::to_string(spaces));
  for (int i = static_cast<int>(ndim) - 1, s = 0; i >= 0; --i) {
    if (axes[i].role != Role::kSpace) continue;
    if (s != static_cast<int>(ndim) - 1 - i)
      return unsupported(g.what + ": 'multiscales'[0]: 'axes': space axes must come last ([t][c][z]yx)");
    img->space_axis_[s++] = i;
  }

  // Scale and translation of each level, per array axis.
  std::vector<double> ms_scale(ndim, 1.0), ms_trans(ndim, 0.0);
  bool ms_has_scale = false;
  if (!g.is_array && ms.contains("coordinateTransformations"))
    VXR_RETURN_IF_ERROR(parse_transforms(ms.at("coordinateTransformations"), ndim, g.what,
                                         "'multiscales'[0]: 'coordinateTransformations'", ms_scale, ms_trans,
                                         ms_has_scale));
  bool all_scaled = true;
  std::vector<std::vector<double>> level_scale;
  for (size_t l = 0; l < img->levels_.size(); ++l) {
    std::vector<double> s(ndim, 1.0), t(ndim, 0.0);
    bool has_scale = false;
    if (!g.is_array && ms.at("datasets")[l].contains("coordinateTransformations"))
      VXR_RETURN_IF_ERROR(parse_transforms(
          ms.at("datasets")[l].at("coordinateTransformations"), ndim, g.what,
          "'multiscales'[0]: 'datasets'[" + std::to_string(l) + "]: 'coordinateTransformations'", s, t, has_scale));
    all_scaled = all_scaled && has_scale;
    OmeLevel& L = img->levels_[l];
    const ArrayMeta& m = L.array->meta();
    for (int a = 0; a < 3; ++a) {
      const int ax = img->space_axis_[a];
      if (ax < 0) continue;
      L.dims[a] = m.shape[ax];
      // The multiscale's own transforms apply after the dataset's.
      L.scale[a] = s[ax] * ms_scale[ax];
      L.translation[a] = t[ax] * ms_scale[ax] + ms_trans[ax];
    }
    level_scale.push_back(s);
  }
  OmeLevel& L0 = img->levels_[0];
  for (OmeLevel& L : img->levels_)
    for (int a = 0; a < 3; ++a) {
      // Factors from the scales (what the spec says), else from the shapes.
      L.factor[a] =
          all_scaled ? L.scale[a] / L0.scale[a] : double(L0.dims[a]) / double(std::max<uint64_t>(1, L.dims[a]));
      if (img->space_axis_[a] < 0) L.factor[a] = 1.0;
    }

  // Units: one for the volume; axes in different units are converted to um.
  std::vector<std::optional<LengthUnit>> units;
  bool same = true;
  for (int a = 0; a < 3; ++a) {
    const int ax = img->space_axis_[a];
    if (ax < 0) continue;
    units.push_back(axes[ax].unit.empty() ? std::nullopt : parse_length_unit(axes[ax].unit));
    if (!axes[ax].unit.empty() && !units.back())
      img->warnings_.push_back("axis '" + axes[ax].name + "' has unit '" + axes[ax].unit +
                               "', not a length; voxel sizes are taken as unitless");
    if (units.size() > 1 &&
        (!units.back() != !units.front() || (units.back() && units.back()->name != units.front()->name)))
      same = false;
  }
  VolumeInfo& info = img->info_;
  info.dtype = m0.dtype;
  info.dims = L0.dims;
  info.channels = img->c_axis_ >= 0 ? static_cast<uint32_t>(m0.shape[img->c_axis_]) : 1;
  info.timepoints = img->t_axis_ >= 0 ? static_cast<uint32_t>(m0.shape[img->t_axis_]) : 1;
  info.voxel_size = L0.scale;
  info.origin = L0.translation;
  if (img->space_axis_[2] < 0) info.voxel_size[2] = info.voxel_size[0];  // 2-D: one slice as thick as a pixel is wide
  if (same && units.front()) {
    info.unit = units.front()->name;
  } else if (!same) {
    info.unit = "um";
    size_t k = 0;
    for (int a = 0; a < 3; ++a)
      if (img->space_axis_[a] >= 0) {
        if (units[k]) info.voxel_size[a] *= units[k]->um, info.origin[a] *= units[k]->um;
        ++k;
      }
    img->warnings_.push_back("space axes have different units; voxel sizes converted to um");
  } else {
    info.unit = "px";
  }
  info.channel_display = omero_channel_display(g.attrs, info.channels, img->warnings_);
  for (int a = 0; a < 3; ++a)
    if (info.dims[a] > (uint64_t(1) << 32))
      return unsupported(g.what + ": level 0 is " + std::to_string(info.dims[a]) + " voxels along " + "xyz"[a] +
                         "; vxr reads up to 2^32 voxels a side");
  if ((img->c_axis_ >= 0 && m0.shape[img->c_axis_] > 65536) || (img->t_axis_ >= 0 && m0.shape[img->t_axis_] > 65536))
    return unsupported(g.what + ": more than 65536 channels or timepoints");
  if (info.channels == 0 || info.timepoints == 0 || info.voxels_per_volume() == 0)
    return bad(g.what, "the image is empty (a dimension of level 0 is 0)");
  return img;
}

std::vector<std::string> OmeZarrImage::metadata_files() const {
  std::vector<std::string> folders{root_, root_ + "/0"};  // "0": a bioformats2raw image
  for (const OmeLevel& L : levels_) folders.push_back(L.path.empty() ? root_ : root_ + "/" + L.path);
  std::vector<std::string> out;
  std::error_code ec;
  for (const std::string& f : folders)
    for (const char* name : {"zarr.json", ".zattrs", ".zgroup", ".zarray", ".zmetadata"})
      if (const std::string p = f + "/" + name;
          fs::is_regular_file(p, ec) && std::find(out.begin(), out.end(), p) == out.end())
        out.push_back(p);
  return out;
}

Status OmeZarrImage::read_region(uint32_t level, uint32_t channel, uint32_t timepoint, const Box3& box,
                                 std::span<uint8_t> dst) const {
  if (level >= levels_.size()) return out_of_range(root_ + ": no level " + std::to_string(level));
  if (channel >= info_.channels || timepoint >= info_.timepoints)
    return out_of_range(root_ + ": channel " + std::to_string(channel) + " / timepoint " + std::to_string(timepoint) +
                        " is outside the image");
  const OmeLevel& L = levels_[level];
  const size_t n = L.array->ndim();
  std::vector<uint64_t> start(n, 0), size(n, 1);
  if (t_axis_ >= 0) start[t_axis_] = timepoint;
  if (c_axis_ >= 0) start[c_axis_] = channel;
  for (int a = 0; a < 3; ++a) {
    if (space_axis_[a] < 0) {
      if (box.origin[a] != 0 || box.size[a] != 1) return out_of_range(root_ + ": read outside the image");
      continue;
    }
    start[space_axis_[a]] = box.origin[a];
    size[space_axis_[a]] = box.size[a];
  }
  // With t and c one voxel thick and the space axes last, the array's C order is x fastest.
  return L.array->read(start, size, dst);
}

}  // namespace vxr::zarr
