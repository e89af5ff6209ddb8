#include "annotate/obj.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <map>
#include <set>
#include <sstream>

#include "annotate/file_io.h"

namespace vxr::annotate {
namespace {

std::vector<std::string_view> split(std::string_view line) {
  std::vector<std::string_view> out;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
    const size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t' && line[i] != '\r') ++i;
    if (i > start) out.push_back(line.substr(start, i - start));
  }
  return out;
}

bool parse_double(std::string_view s, double& v) {
  const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  return ec == std::errc() && p == s.data() + s.size() && std::isfinite(v);
}

// Kd per material name from an .mtl file; warnings for what cannot be used.
std::map<std::string, std::array<float, 3>> read_mtl(const std::string& path, std::vector<std::string>& warnings) {
  std::map<std::string, std::array<float, 3>> out;
  auto text = read_whole_file(path);
  if (!text.is_ok()) {
    warnings.push_back(text.status().message() + " (materials are drawn grey)");
    return out;
  }
  std::istringstream in(*text);
  std::string line, current;
  for (int n = 1; std::getline(in, line); ++n) {
    const auto t = split(line);
    if (t.empty()) continue;
    if (t[0] == "newmtl" && t.size() >= 2) current = std::string(t[1]);
    if (t[0] == "Kd" && t.size() >= 4 && !current.empty()) {
      std::array<double, 3> c{};
      bool ok = true;
      for (int i = 0; i < 3; ++i) ok = ok && parse_double(t[1 + i], c[i]);
      if (ok) out[current] = {float(std::clamp(c[0], 0.0, 1.0)), float(std::clamp(c[1], 0.0, 1.0)),
                              float(std::clamp(c[2], 0.0, 1.0))};
      else warnings.push_back(path + ":" + std::to_string(n) + ": Kd is not three numbers; ignored");
    }
  }
  return out;
}

}  // namespace

Result<ObjResult> parse_obj(const std::string& text, const std::string& source, const std::string& mtl_dir) {
  ObjResult r;
  Mesh& m = r.mesh;
  m.materials.push_back({"", {0.8f, 0.8f, 0.8f}});
  std::map<std::string, std::array<float, 3>> library;
  std::set<std::string> warned_keywords;
  uint32_t material = 0;
  int current_object = -1;
  auto open_part = [&](std::string name, int parent) {
    // An unnamed part that got no faces is dropped; a part opened under it hangs where it would have.
    if (!m.parts.empty() && m.parts.back().triangle_count == 0 && m.parts.back().name.empty()) {
      const int dropped = int(m.parts.size()) - 1;
      if (parent == dropped) parent = m.parts.back().parent;
      if (current_object == dropped) current_object = -1;
      m.parts.pop_back();
    }
    m.parts.push_back({std::move(name), parent, uint32_t(m.triangles.size()), 0});
    return int(m.parts.size()) - 1;
  };
  std::istringstream in(text);
  std::string line;
  int n = 0;
  auto where = [&] { return source + ":" + std::to_string(n) + ": "; };
  std::vector<uint32_t> poly;
  while (std::getline(in, line)) {
    ++n;
    const auto t = split(line);
    if (t.empty() || t[0][0] == '#') continue;
    const std::string_view k = t[0];
    if (k == "v") {
      if (t.size() < 4) return corrupt(where() + "a vertex needs x y z");
      Vec3 p{};
      for (int i = 0; i < 3; ++i)
        if (!parse_double(t[1 + i], p[i])) return corrupt(where() + "vertex coordinate '" + std::string(t[1 + i]) + "' is not a finite number");
      m.positions.push_back(p);
    } else if (k == "f") {
      poly.clear();
      for (size_t i = 1; i < t.size(); ++i) {
        const std::string_view idx = t[i].substr(0, t[i].find('/'));
        long long v = 0;
        const auto [p, ec] = std::from_chars(idx.data(), idx.data() + idx.size(), v);
        if (ec != std::errc() || p != idx.data() + idx.size() || v == 0)
          return corrupt(where() + "face vertex '" + std::string(t[i]) + "' is not a vertex index");
        const long long count = (long long)m.positions.size();
        const long long abs = v > 0 ? v - 1 : count + v;  // negative: relative to the vertices so far
        if (abs < 0 || abs >= count)
          return corrupt(where() + "face vertex " + std::to_string(v) + " is outside the " + std::to_string(count) +
                         " vertices read so far");
        poly.push_back(uint32_t(abs));
      }
      if (poly.size() < 3) {
        r.warnings.push_back(where() + "a face with fewer than 3 vertices; skipped");
        continue;
      }
      if (m.parts.empty()) open_part("", -1);
      for (size_t i = 1; i + 1 < poly.size(); ++i) {  // a fan: OBJ polygons are planar and convex
        m.triangles.push_back({poly[0], poly[i], poly[i + 1]});
        m.triangle_material.push_back(material);
        ++m.parts.back().triangle_count;
      }
    } else if (k == "o") {
      current_object = open_part(t.size() > 1 ? std::string(t[1]) : "", -1);
    } else if (k == "g") {
      open_part(t.size() > 1 ? std::string(t[1]) : "", current_object);
    } else if (k == "mtllib") {
      if (mtl_dir.empty() || t.size() < 2) continue;
      for (const auto& [name, c] : read_mtl((std::filesystem::path(mtl_dir) / std::string(t[1])).string(), r.warnings))
        library[name] = c;
    } else if (k == "usemtl") {
      const std::string name = t.size() > 1 ? std::string(t[1]) : "";
      auto it = library.find(name);
      if (it == library.end()) {
        r.warnings.push_back(where() + "material '" + name + "' is not in a material library; drawn grey");
        material = 0;
        continue;
      }
      material = 0;
      for (uint32_t i = 1; i < m.materials.size(); ++i)
        if (m.materials[i].name == name) material = i;
      if (material == 0) {
        m.materials.push_back({name, it->second});
        material = uint32_t(m.materials.size() - 1);
      }
    } else if (k == "vt" || k == "vn" || k == "s" || k == "l" || k == "p" || k == "vp") {
      // Texture coordinates, normals, smoothing groups, lines, points: not drawn.
    } else if (warned_keywords.insert(std::string(k)).second) {
      r.warnings.push_back(where() + "unknown keyword '" + std::string(k) + "'; lines with it are skipped");
    }
  }
  if (m.triangles.empty()) return corrupt(source + ": has no faces to draw");
  // A trailing unnamed part with no faces says nothing (parents come before their children, so it has none).
  if (!m.parts.empty() && m.parts.back().triangle_count == 0 && m.parts.back().name.empty()) m.parts.pop_back();
  return r;
}

Result<ObjResult> read_obj(const std::string& path) {
  VXR_ASSIGN_OR_RETURN(std::string text, read_whole_file(path));
  return parse_obj(text, path, std::filesystem::path(path).parent_path().string());
}

}  // namespace vxr::annotate
