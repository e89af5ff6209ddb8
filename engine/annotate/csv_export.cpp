#include "annotate/csv_export.h"

#include <charconv>
#include <map>

namespace vxr::annotate {

namespace {
std::string num(double v) {
  char buf[64];
  const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v);
  return ec == std::errc() ? std::string(buf, end) : std::string();
}
std::string unit_suffix(const VoxelSpace& space) {
  return csv_field(space.unit);
}
}  // namespace

std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\r\n") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

std::string markers_csv(const std::vector<Marker>& markers, const VoxelSpace& space) {
  const std::string u = unit_suffix(space);
  std::string out = "id,class,r,g,b,a,x,y,z,timepoint,x_" + u + ",y_" + u + ",z_" + u + "\n";
  for (const Marker& m : markers) {
    const Vec3 p = space.to_physical(m.pos);
    out += std::to_string(m.id) + ',' + csv_field(m.cls);
    for (double c : m.color) out += ',' + num(c);
    for (double c : m.pos) out += ',' + num(c);
    out += ',' + std::to_string(m.timepoint);
    for (double c : p) out += ',' + num(c);
    out += '\n';
  }
  return out;
}

std::string counts_csv(const std::vector<Marker>& markers, int64_t timepoint) {
  std::map<std::string, size_t> counts;
  for (const Marker& m : markers)
    if (timepoint < 0 || m.timepoint == timepoint) ++counts[m.cls];
  std::string out = "class,count\n";
  for (const auto& [cls, n] : counts) out += csv_field(cls) + ',' + std::to_string(n) + '\n';
  return out;
}

std::string measurements_csv(const std::vector<Measurement>& measurements, const VoxelSpace& space) {
  std::string out = "id,label,timepoint,ax,ay,az,bx,by,bz,length_" + unit_suffix(space) + "\n";
  for (const Measurement& m : measurements) {
    out += std::to_string(m.id) + ',' + csv_field(m.label) + ',' + std::to_string(m.timepoint);
    for (double c : m.a) out += ',' + num(c);
    for (double c : m.b) out += ',' + num(c);
    out += ',' + num(space.distance(m.a, m.b)) + '\n';
  }
  return out;
}

std::string tracks_csv(const std::vector<Track>& tracks, const std::vector<Marker>& markers, const VoxelSpace& space) {
  std::map<Id, const Marker*> by_id;
  for (const Marker& m : markers) by_id[m.id] = &m;
  std::string out = "track,name,step,marker,timepoint,x,y,z,step_length_" + unit_suffix(space) + "\n";
  for (const Track& t : tracks) {
    const Marker* prev = nullptr;
    int step = 0;
    for (Id id : t.markers) {
      auto it = by_id.find(id);
      if (it == by_id.end()) continue;
      const Marker& m = *it->second;
      out += std::to_string(t.id) + ',' + csv_field(t.name) + ',' + std::to_string(step++) + ',' +
             std::to_string(m.id) + ',' + std::to_string(m.timepoint);
      for (double c : m.pos) out += ',' + num(c);
      out += ',' + (prev ? num(space.distance(prev->pos, m.pos)) : std::string()) + '\n';
      prev = &m;
    }
  }
  return out;
}

}  // namespace vxr::annotate
