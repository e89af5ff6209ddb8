#include "annotate/annotation_store.h"

#include <leveldb/db.h>
#include <leveldb/write_batch.h>

#include <algorithm>
#include <cstring>
#include <cctype>
#include <cinttypes>
#include <cstdio>
#include <ctime>
#include <nlohmann/json.hpp>
#include <set>

#include "scene/render_settings.h"

namespace vxr::annotate {

using nlohmann::json;

namespace {

// Keys: "<kind>/<16 hex digits>" so LevelDB's byte order is numeric order.
std::string hex16(uint64_t v) {
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016" PRIx64, v);
  return buf;
}
Id parse_hex16(const std::string& s) {
  return std::strtoull(s.c_str(), nullptr, 16);
}

const std::string kSchemaKey = "meta/schema_version";
const std::string kSpaceKey = "meta/voxel_space";
const std::string kNextPrefix = "meta/next/";
std::string marker_key(Id id) {
  return "marker/" + hex16(id);
}
std::string measure_key(Id id) {
  return "measure/" + hex16(id);
}
std::string skeleton_key(Id id) {
  return "skeleton/" + hex16(id);
}
std::string node_prefix(Id sk) {
  return "node/" + hex16(sk) + "/";
}
std::string node_key(Id sk, int64_t node) {
  return node_prefix(sk) + hex16(static_cast<uint64_t>(node));
}
std::string track_key(Id id) {
  return "track/" + hex16(id);
}
std::string roi_key(Id id) {
  return "roi/" + hex16(id);
}
std::string card_key(Id id) {
  return "card/" + hex16(id);
}
std::string mesh_key(Id id) {
  return "mesh/" + hex16(id);
}
std::string mesh_data_key(Id id) {
  return "meshdata/" + hex16(id);
}
std::string blob_key(Id id, const char* what) {
  return "blob/" + hex16(id) + "/" + what;
}

json vec(const Vec3& v) {
  return json::array({v[0], v[1], v[2]});
}

// Value decoding: a wrong shape is corruption of the store, named by key.
struct BadValue {
  std::string what;
};
Vec3 get_vec3(const json& j, const char* key) {
  const json& a = j.at(key);
  if (!a.is_array() || a.size() != 3) throw BadValue{std::string(key) + " is not 3 numbers"};
  return {a[0].get<double>(), a[1].get<double>(), a[2].get<double>()};
}

json marker_json(const Marker& m) {
  return {{"class", m.cls}, {"color", m.color}, {"pos", vec(m.pos)}, {"t", m.timepoint}};
}
Marker marker_from(Id id, const json& j) {
  Marker m;
  m.id = id;
  m.cls = j.at("class").get<std::string>();
  m.color = j.at("color").get<std::array<double, 4>>();
  m.pos = get_vec3(j, "pos");
  m.timepoint = j.at("t").get<uint32_t>();
  return m;
}
json measure_json(const Measurement& m) {
  return {{"label", m.label}, {"a", vec(m.a)}, {"b", vec(m.b)}, {"t", m.timepoint}};
}
Measurement measure_from(Id id, const json& j) {
  return {id, j.at("label").get<std::string>(), get_vec3(j, "a"), get_vec3(j, "b"), j.at("t").get<uint32_t>()};
}
json node_json(const SkeletonNode& n) {
  return {{"pos", vec(n.pos)}, {"r", n.radius}, {"type", n.type}, {"parent", n.parent}};
}
SkeletonNode node_from(int64_t id, const json& j) {
  return {id, get_vec3(j, "pos"), j.at("r").get<double>(), j.at("type").get<int>(), j.at("parent").get<int64_t>()};
}
json roi_json(const Roi& r) {
  return {{"name", r.name}, {"min", vec(r.min)}, {"max", vec(r.max)}};
}
Roi roi_from(Id id, const json& j) {
  return {id, j.at("name").get<std::string>(), get_vec3(j, "min"), get_vec3(j, "max")};
}
json track_json(const Track& t) {
  return {{"name", t.name}, {"markers", t.markers}};
}
Track track_from(Id id, const json& j) {
  return {id, j.at("name").get<std::string>(), j.at("markers").get<std::vector<Id>>()};
}
json card_json(const Card& c) {
  return {{"title", c.title},
          {"note", c.note},
          {"scene", c.scene_json},
          {"created", c.created_unix},
          {"snapshot_path", c.snapshot_path},
          {"snapshot_bytes", c.snapshot_png.size()},
          {"audio_bytes", c.audio_wav.size()}};
}

json mesh_json(const StoredMesh& m) {
  return {{"name", m.name}, {"parent", m.parent}, {"color", m.color}, {"vertices", m.vertices},
          {"triangles", m.triangles}};
}
StoredMesh mesh_from(Id id, const json& j) {
  return {id, j.at("name").get<std::string>(), j.at("parent").get<Id>(), j.at("color").get<std::array<double, 4>>(),
          j.at("vertices").get<uint64_t>(), j.at("triangles").get<uint64_t>()};
}

// meshdata/<id>: little-endian u32 vertex count, u32 triangle count, the
// positions as f64 x y z, the triangles as u32 a b c.
std::string encode_mesh_data(const std::vector<Vec3>& positions, const std::vector<std::array<uint32_t, 3>>& tris) {
  std::string out(8 + positions.size() * 24 + tris.size() * 12, '\0');
  const uint32_t counts[2] = {uint32_t(positions.size()), uint32_t(tris.size())};
  std::memcpy(out.data(), counts, 8);
  // An empty part (no vertices) has null data(): memcpy must not see it.
  if (!positions.empty()) std::memcpy(out.data() + 8, positions.data(), positions.size() * 24);
  if (!tris.empty()) std::memcpy(out.data() + 8 + positions.size() * 24, tris.data(), tris.size() * 12);
  return out;
}

template <typename T, typename F>
Result<T> decode(const std::string& store, const std::string& key, const std::string& value, F&& fn) {
  try {
    return fn(json::parse(value));
  } catch (const BadValue& e) {
    return corrupt(store + ": key " + key + ": " + e.what + "; the store is damaged (restore it from a backup)");
  } catch (const json::exception& e) {
    return corrupt(store + ": key " + key + ": unreadable value (" + e.what() +
                   "); the store is damaged (restore it from a backup)");
  }
}

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

bool is_png(const std::vector<uint8_t>& b) {
  static const uint8_t sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  return b.size() >= 8 && std::equal(sig, sig + 8, b.begin());
}
bool is_wav(const std::vector<uint8_t>& b) {
  return b.size() >= 12 && std::equal(b.begin(), b.begin() + 4, "RIFF") &&
         std::equal(b.begin() + 8, b.begin() + 12, "WAVE");
}

Status finite3(const Vec3& v, const char* what) {
  for (double d : v)
    if (!std::isfinite(d)) return invalid_argument(std::string(what) + " must be finite numbers");
  return Status::ok();
}

}  // namespace

Result<std::unique_ptr<AnnotationStore>> AnnotationStore::open(const std::string& path, bool create_if_missing) {
  leveldb::Options options;
  options.create_if_missing = create_if_missing;
  options.paranoid_checks = true;  // a damaged log or table fails the open instead of being skipped
  leveldb::DB* raw = nullptr;
  const leveldb::Status s = leveldb::DB::Open(options, path, &raw);
  if (!s.ok()) {
    const std::string why = s.ToString();
    if (s.IsInvalidArgument() && why.find("does not exist") != std::string::npos) {
      return not_found(path + ": no annotation store here (create one with `vxr annotate init " + path + "`)");
    }
    if (s.IsIOError() && why.find("lock") != std::string::npos) {
      return io_error(path + ": the annotation store is open in another process (" + why + "); close that first");
    }
    if (s.IsCorruption())
      return corrupt(path + ": annotation store is damaged (" + why + "); restore it from a backup");
    return io_error(path + ": cannot open the annotation store (" + why + ")");
  }
  std::unique_ptr<AnnotationStore> store(new AnnotationStore(path, raw));
  VXR_RETURN_IF_ERROR(store->init());
  return store;
}

AnnotationStore::~AnnotationStore() {
  delete db_;
}

Status AnnotationStore::init() {
  VXR_ASSIGN_OR_RETURN(std::optional<std::string> version, get(kSchemaKey));
  if (!version) {
    // Only an empty database may become a store: anything else is someone else's LevelDB.
    leveldb::ReadOptions ro;
    ro.verify_checksums = true;
    std::unique_ptr<leveldb::Iterator> it(db_->NewIterator(ro));
    it->SeekToFirst();
    if (it->Valid()) {
      return corrupt(path_ + ": a LevelDB database without '" + kSchemaKey + "' is not a vxr annotation store");
    }
    leveldb::WriteBatch batch;
    batch.Put(kSchemaKey, std::to_string(kSchemaVersion));
    batch.Put(kSpaceKey, json{{"voxel_size", vec(space_.voxel_size)}, {"unit", space_.unit}}.dump());
    return write(&batch);
  }
  char* end = nullptr;
  const long v = std::strtol(version->c_str(), &end, 10);
  if (version->empty() || *end != '\0' || v < 1) {
    return corrupt(path_ + ": schema version '" + *version + "' is not a number; the store is damaged");
  }
  if (v > kSchemaVersion) {
    return unsupported(path_ + ": annotation store schema version " + std::to_string(v) +
                       " is newer than this vxr reads (version " + std::to_string(kSchemaVersion) +
                       "); open it with a newer vxr");
  }
  if (auto sp = get(kSpaceKey); !sp.is_ok()) {
    return sp.status();
  } else if (*sp) {
    auto space = decode<VoxelSpace>(path_, kSpaceKey, **sp, [](const json& j) {
      VoxelSpace vs;
      vs.voxel_size = get_vec3(j, "voxel_size");
      vs.unit = j.at("unit").get<std::string>();
      return vs;
    });
    if (!space.is_ok()) return space.status();
    space_ = *space;
  }
  return scan(kNextPrefix, [&](const std::string& key, const std::string& value) {
    next_[key.substr(kNextPrefix.size())] = std::strtoull(value.c_str(), nullptr, 10);
    return Status::ok();
  });
}

Status AnnotationStore::write(leveldb::WriteBatch* batch) {
  leveldb::WriteOptions wo;
  wo.sync = true;  // the edit is on disk when we return: a kill -9 cannot lose an acknowledged write
  const leveldb::Status s = db_->Write(wo, batch);
  if (!s.ok()) return io_error(path_ + ": write failed (" + s.ToString() + ")");
  return Status::ok();
}

Result<std::optional<std::string>> AnnotationStore::get(const std::string& key) const {
  leveldb::ReadOptions ro;
  ro.verify_checksums = true;
  std::string value;
  const leveldb::Status s = db_->Get(ro, key, &value);
  if (s.IsNotFound()) return std::optional<std::string>();
  if (!s.ok()) return corrupt(path_ + ": reading " + key + " failed (" + s.ToString() + ")");
  return std::optional<std::string>(std::move(value));
}

Status AnnotationStore::scan(const std::string& prefix,
                             const std::function<Status(const std::string&, const std::string&)>& fn) const {
  leveldb::ReadOptions ro;
  ro.verify_checksums = true;
  std::unique_ptr<leveldb::Iterator> it(db_->NewIterator(ro));
  for (it->Seek(prefix); it->Valid() && it->key().starts_with(prefix); it->Next()) {
    VXR_RETURN_IF_ERROR(fn(it->key().ToString(), it->value().ToString()));
  }
  if (!it->status().ok()) return corrupt(path_ + ": reading " + prefix + "* failed (" + it->status().ToString() + ")");
  return Status::ok();
}

Result<Id> AnnotationStore::next_id(const std::string& kind, leveldb::WriteBatch* batch) {
  // The counter is written in the same batch as the object, so a crash can
  // never leave an object whose id would be handed out again.
  Id& next = next_[kind];
  if (next == 0) next = 1;
  const Id id = next++;
  batch->Put(kNextPrefix + kind, std::to_string(next));
  return id;
}

Status AnnotationStore::not_there(const std::string& kind, Id id) const {
  return not_found(path_ + ": no " + kind + " " + std::to_string(id));
}

Status AnnotationStore::set_voxel_space(const VoxelSpace& space) {
  for (double d : space.voxel_size)
    if (!(d > 0) || !std::isfinite(d)) return invalid_argument("voxel size must be three positive numbers");
  if (micrometres_per_unit(space.unit) == 0) {
    return invalid_argument("unit '" + space.unit + "' is not one of um, nm, mm");
  }
  leveldb::WriteBatch batch;
  batch.Put(kSpaceKey, json{{"voxel_size", vec(space.voxel_size)}, {"unit", space.unit}}.dump());
  VXR_RETURN_IF_ERROR(write(&batch));
  space_ = space;
  return Status::ok();
}

// ---- markers ----

Result<Id> AnnotationStore::add_marker(Marker m) {
  VXR_RETURN_IF_ERROR(finite3(m.pos, "marker position"));
  leveldb::WriteBatch batch;
  VXR_ASSIGN_OR_RETURN(m.id, next_id("marker", &batch));
  batch.Put(marker_key(m.id), marker_json(m).dump());
  VXR_RETURN_IF_ERROR(write(&batch));
  return m.id;
}

Status AnnotationStore::update_marker(const Marker& m) {
  VXR_RETURN_IF_ERROR(finite3(m.pos, "marker position"));
  VXR_ASSIGN_OR_RETURN(Marker old, marker(m.id));
  if (old.timepoint != m.timepoint) {
    // A track holds one marker per timepoint; moving in time could break that.
    VXR_ASSIGN_OR_RETURN(std::vector<Track> all, tracks());
    for (const Track& t : all)
      if (std::find(t.markers.begin(), t.markers.end(), m.id) != t.markers.end())
        return invalid_argument("marker " + std::to_string(m.id) + " is in track " + std::to_string(t.id) +
                                "; its timepoint cannot change");
  }
  leveldb::WriteBatch batch;
  batch.Put(marker_key(m.id), marker_json(m).dump());
  return write(&batch);
}

Status AnnotationStore::delete_marker(Id id) {
  VXR_ASSIGN_OR_RETURN(Marker old, marker(id));
  (void)old;
  VXR_ASSIGN_OR_RETURN(std::vector<Track> all, tracks());
  leveldb::WriteBatch batch;
  batch.Delete(marker_key(id));
  for (Track t : all) {
    auto it = std::find(t.markers.begin(), t.markers.end(), id);
    if (it == t.markers.end()) continue;
    t.markers.erase(it);
    batch.Put(track_key(t.id), track_json(t).dump());
  }
  return write(&batch);
}

Result<Marker> AnnotationStore::marker(Id id) const {
  VXR_ASSIGN_OR_RETURN(std::optional<std::string> v, get(marker_key(id)));
  if (!v) return not_there("marker", id);
  return decode<Marker>(path_, marker_key(id), *v, [&](const json& j) { return marker_from(id, j); });
}

Result<std::vector<Marker>> AnnotationStore::markers() const {
  std::vector<Marker> out;
  VXR_RETURN_IF_ERROR(scan("marker/", [&](const std::string& k, const std::string& v) {
    auto m = decode<Marker>(path_, k, v, [&](const json& j) { return marker_from(parse_hex16(k.substr(7)), j); });
    if (!m.is_ok()) return m.status();
    out.push_back(std::move(*m));
    return Status::ok();
  }));
  return out;
}

Result<std::map<std::string, size_t>> AnnotationStore::counts(std::optional<uint32_t> timepoint) const {
  VXR_ASSIGN_OR_RETURN(std::vector<Marker> all, markers());
  std::map<std::string, size_t> out;
  for (const Marker& m : all)
    if (!timepoint || m.timepoint == *timepoint) ++out[m.cls];
  return out;
}

// ---- measurements ----

Result<Id> AnnotationStore::add_measurement(Measurement m) {
  VXR_RETURN_IF_ERROR(finite3(m.a, "measurement point"));
  VXR_RETURN_IF_ERROR(finite3(m.b, "measurement point"));
  leveldb::WriteBatch batch;
  VXR_ASSIGN_OR_RETURN(m.id, next_id("measure", &batch));
  batch.Put(measure_key(m.id), measure_json(m).dump());
  VXR_RETURN_IF_ERROR(write(&batch));
  return m.id;
}

Status AnnotationStore::delete_measurement(Id id) {
  VXR_ASSIGN_OR_RETURN(Measurement old, measurement(id));
  (void)old;
  leveldb::WriteBatch batch;
  batch.Delete(measure_key(id));
  return write(&batch);
}

Result<Measurement> AnnotationStore::measurement(Id id) const {
  VXR_ASSIGN_OR_RETURN(std::optional<std::string> v, get(measure_key(id)));
  if (!v) return not_there("measurement", id);
  return decode<Measurement>(path_, measure_key(id), *v, [&](const json& j) { return measure_from(id, j); });
}

Result<std::vector<Measurement>> AnnotationStore::measurements() const {
  std::vector<Measurement> out;
  VXR_RETURN_IF_ERROR(scan("measure/", [&](const std::string& k, const std::string& v) {
    auto m = decode<Measurement>(path_, k, v, [&](const json& j) { return measure_from(parse_hex16(k.substr(8)), j); });
    if (!m.is_ok()) return m.status();
    out.push_back(std::move(*m));
    return Status::ok();
  }));
  return out;
}

// ---- skeletons ----

Result<Id> AnnotationStore::add_skeleton(const Skeleton& sk) {
  VXR_RETURN_IF_ERROR(sk.validate());
  for (const auto& [nid, n] : sk.nodes()) VXR_RETURN_IF_ERROR(finite3(n.pos, "node position"));
  leveldb::WriteBatch batch;
  VXR_ASSIGN_OR_RETURN(Id id, next_id("skeleton", &batch));
  batch.Put(skeleton_key(id), json{{"name", sk.name()}}.dump());
  for (const auto& [nid, n] : sk.nodes()) batch.Put(node_key(id, nid), node_json(n).dump());
  VXR_RETURN_IF_ERROR(write(&batch));
  return id;
}

Result<Skeleton> AnnotationStore::skeleton(Id id) const {
  VXR_ASSIGN_OR_RETURN(std::optional<std::string> v, get(skeleton_key(id)));
  if (!v) return not_there("skeleton", id);
  VXR_ASSIGN_OR_RETURN(std::string name, decode<std::string>(path_, skeleton_key(id), *v, [](const json& j) {
                         return j.at("name").get<std::string>();
                       }));
  Skeleton sk(id, name);
  const std::string prefix = node_prefix(id);
  VXR_RETURN_IF_ERROR(scan(prefix, [&](const std::string& k, const std::string& val) {
    const int64_t nid = static_cast<int64_t>(parse_hex16(k.substr(prefix.size())));
    auto n = decode<SkeletonNode>(path_, k, val, [&](const json& j) { return node_from(nid, j); });
    if (!n.is_ok()) return n.status();
    sk.insert_unchecked(*n);
    return Status::ok();
  }));
  if (Status s = sk.validate(); !s.is_ok()) return corrupt(path_ + ": " + s.message());
  return sk;
}

Result<std::vector<SkeletonInfo>> AnnotationStore::skeletons() const {
  std::vector<SkeletonInfo> out;
  VXR_RETURN_IF_ERROR(scan("skeleton/", [&](const std::string& k, const std::string& v) {
    auto name = decode<std::string>(path_, k, v, [](const json& j) { return j.at("name").get<std::string>(); });
    if (!name.is_ok()) return name.status();
    out.push_back({parse_hex16(k.substr(9)), *name});
    return Status::ok();
  }));
  return out;
}

Status AnnotationStore::delete_skeleton(Id id) {
  VXR_ASSIGN_OR_RETURN(Skeleton sk, skeleton(id));
  leveldb::WriteBatch batch;
  batch.Delete(skeleton_key(id));
  for (const auto& [nid, n] : sk.nodes()) batch.Delete(node_key(id, nid));
  return write(&batch);
}

Status AnnotationStore::write_skeleton_diff(const Skeleton& before, const Skeleton& after, leveldb::WriteBatch* batch) {
  for (const auto& [nid, n] : before.nodes())
    if (!after.find(nid)) batch->Delete(node_key(after.id(), nid));
  for (const auto& [nid, n] : after.nodes()) {
    VXR_RETURN_IF_ERROR(finite3(n.pos, "node position"));
    const SkeletonNode* old = before.find(nid);
    if (!old || !(*old == n)) batch->Put(node_key(after.id(), nid), node_json(n).dump());
  }
  return Status::ok();
}

Status AnnotationStore::edit_skeleton(Id id, const std::function<Status(Skeleton&)>& edit) {
  VXR_ASSIGN_OR_RETURN(Skeleton before, skeleton(id));
  Skeleton after = before;
  if (Status s = edit(after); !s.is_ok()) return Status(s.code(), path_ + ": " + s.message());
  if (Status s = after.validate(); !s.is_ok()) return internal_error("skeleton edit broke the tree: " + s.message());
  leveldb::WriteBatch batch;
  VXR_RETURN_IF_ERROR(write_skeleton_diff(before, after, &batch));
  return write(&batch);
}

Result<int64_t> AnnotationStore::add_node(Id skeleton, SkeletonNode node) {
  int64_t added = 0;
  VXR_RETURN_IF_ERROR(edit_skeleton(skeleton, [&](Skeleton& sk) -> Status {
    VXR_ASSIGN_OR_RETURN(added, sk.add_node(node));
    return Status::ok();
  }));
  return added;
}

Status AnnotationStore::move_node(Id skeleton, int64_t node, const Vec3& pos) {
  return edit_skeleton(skeleton, [&](Skeleton& sk) { return sk.move_node(node, pos); });
}

Status AnnotationStore::delete_node(Id skeleton, int64_t node) {
  return edit_skeleton(skeleton, [&](Skeleton& sk) { return sk.delete_node(node); });
}

Status AnnotationStore::reparent_node(Id skeleton, int64_t node, int64_t new_parent) {
  return edit_skeleton(skeleton, [&](Skeleton& sk) { return sk.reparent(node, new_parent); });
}

Result<Id> AnnotationStore::split_skeleton(Id id, int64_t node) {
  VXR_ASSIGN_OR_RETURN(Skeleton before, skeleton(id));
  Skeleton after = before;
  VXR_ASSIGN_OR_RETURN(Skeleton part, after.split(node));
  leveldb::WriteBatch batch;  // both halves in one batch: a crash leaves the original or the split, never half
  VXR_RETURN_IF_ERROR(write_skeleton_diff(before, after, &batch));
  VXR_ASSIGN_OR_RETURN(Id new_id, next_id("skeleton", &batch));
  batch.Put(skeleton_key(new_id), json{{"name", part.name()}}.dump());
  for (const auto& [nid, n] : part.nodes()) batch.Put(node_key(new_id, nid), node_json(n).dump());
  VXR_RETURN_IF_ERROR(write(&batch));
  return new_id;
}

Result<std::map<int64_t, int64_t>> AnnotationStore::merge_skeletons(Id target, int64_t attach_to, Id source,
                                                                    int64_t source_node) {
  if (target == source) return invalid_argument("cannot merge skeleton " + std::to_string(target) + " into itself");
  VXR_ASSIGN_OR_RETURN(Skeleton before, skeleton(target));
  VXR_ASSIGN_OR_RETURN(Skeleton src, skeleton(source));
  const Skeleton src_before = src;
  Skeleton after = before;
  VXR_ASSIGN_OR_RETURN(auto renumbered, after.merge(src, source_node, attach_to));
  if (Status s = after.validate(); !s.is_ok()) return internal_error("skeleton merge broke the tree: " + s.message());
  leveldb::WriteBatch batch;
  VXR_RETURN_IF_ERROR(write_skeleton_diff(before, after, &batch));
  batch.Delete(skeleton_key(source));
  for (const auto& [nid, n] : src_before.nodes()) batch.Delete(node_key(source, nid));
  VXR_RETURN_IF_ERROR(write(&batch));
  return renumbered;
}

// ---- tracks ----

Status AnnotationStore::check_track_markers(const std::vector<Id>& ids, std::vector<Id>* sorted) const {
  std::vector<Marker> ms;
  for (Id id : ids) {
    VXR_ASSIGN_OR_RETURN(Marker m, marker(id));
    for (const Marker& o : ms)
      if (o.timepoint == m.timepoint)
        return invalid_argument("markers " + std::to_string(o.id) + " and " + std::to_string(m.id) +
                                " are both at timepoint " + std::to_string(m.timepoint) +
                                "; a track holds one marker per timepoint");
    ms.push_back(m);
  }
  std::stable_sort(ms.begin(), ms.end(), [](const Marker& a, const Marker& b) { return a.timepoint < b.timepoint; });
  sorted->clear();
  for (const Marker& m : ms) sorted->push_back(m.id);
  return Status::ok();
}

Result<Id> AnnotationStore::add_track(const std::string& name, const std::vector<Id>& marker_ids) {
  Track t;
  t.name = name;
  VXR_RETURN_IF_ERROR(check_track_markers(marker_ids, &t.markers));
  leveldb::WriteBatch batch;
  VXR_ASSIGN_OR_RETURN(t.id, next_id("track", &batch));
  batch.Put(track_key(t.id), track_json(t).dump());
  VXR_RETURN_IF_ERROR(write(&batch));
  return t.id;
}

Status AnnotationStore::add_to_track(Id track_id, Id marker_id) {
  VXR_ASSIGN_OR_RETURN(Track t, track(track_id));
  std::vector<Id> ids = t.markers;
  ids.push_back(marker_id);
  VXR_RETURN_IF_ERROR(check_track_markers(ids, &t.markers));
  leveldb::WriteBatch batch;
  batch.Put(track_key(t.id), track_json(t).dump());
  return write(&batch);
}

Status AnnotationStore::delete_track(Id id) {
  VXR_ASSIGN_OR_RETURN(Track gone, track(id));
  VXR_ASSIGN_OR_RETURN(std::vector<Track> all, tracks());
  leveldb::WriteBatch batch;
  batch.Delete(track_key(id));
  for (Id m : gone.markers) batch.Delete(marker_key(m));
  // Another track holding one of those markers leaves it, as delete_marker does.
  for (Track t : all) {
    if (t.id == id) continue;
    const size_t before = t.markers.size();
    std::erase_if(t.markers, [&](Id m) { return std::find(gone.markers.begin(), gone.markers.end(), m) != gone.markers.end(); });
    if (t.markers.size() != before) batch.Put(track_key(t.id), track_json(t).dump());
  }
  return write(&batch);
}

Result<Track> AnnotationStore::track(Id id) const {
  VXR_ASSIGN_OR_RETURN(std::optional<std::string> v, get(track_key(id)));
  if (!v) return not_there("track", id);
  return decode<Track>(path_, track_key(id), *v, [&](const json& j) { return track_from(id, j); });
}

Result<std::vector<Track>> AnnotationStore::tracks() const {
  std::vector<Track> out;
  VXR_RETURN_IF_ERROR(scan("track/", [&](const std::string& k, const std::string& v) {
    auto t = decode<Track>(path_, k, v, [&](const json& j) { return track_from(parse_hex16(k.substr(6)), j); });
    if (!t.is_ok()) return t.status();
    out.push_back(std::move(*t));
    return Status::ok();
  }));
  return out;
}

// ---- ROIs ----

Result<Id> AnnotationStore::add_roi(Roi r) {
  VXR_RETURN_IF_ERROR(finite3(r.min, "ROI corner"));
  VXR_RETURN_IF_ERROR(finite3(r.max, "ROI corner"));
  for (int i = 0; i < 3; ++i)
    if (r.min[i] > r.max[i]) return invalid_argument("ROI min must be <= max on every axis");
  leveldb::WriteBatch batch;
  VXR_ASSIGN_OR_RETURN(r.id, next_id("roi", &batch));
  batch.Put(roi_key(r.id), roi_json(r).dump());
  VXR_RETURN_IF_ERROR(write(&batch));
  return r.id;
}

Result<Roi> AnnotationStore::roi(Id id) const {
  VXR_ASSIGN_OR_RETURN(std::optional<std::string> v, get(roi_key(id)));
  if (!v) return not_there("ROI", id);
  return decode<Roi>(path_, roi_key(id), *v, [&](const json& j) { return roi_from(id, j); });
}

Result<std::vector<Roi>> AnnotationStore::rois() const {
  std::vector<Roi> out;
  VXR_RETURN_IF_ERROR(scan("roi/", [&](const std::string& k, const std::string& v) {
    auto r = decode<Roi>(path_, k, v, [&](const json& j) { return roi_from(parse_hex16(k.substr(4)), j); });
    if (!r.is_ok()) return r.status();
    out.push_back(std::move(*r));
    return Status::ok();
  }));
  return out;
}

Status AnnotationStore::delete_roi(Id id) {
  VXR_ASSIGN_OR_RETURN(Roi old, roi(id));
  (void)old;
  leveldb::WriteBatch batch;
  batch.Delete(roi_key(id));
  return write(&batch);
}

Result<std::vector<Id>> AnnotationStore::add_meshes(const Mesh& mesh, double alpha) {
  if (!(alpha >= 0.0 && alpha <= 1.0)) return invalid_argument("mesh opacity must be in 0..1");
  for (const Vec3& p : mesh.positions) VXR_RETURN_IF_ERROR(finite3(p, "mesh vertex"));
  leveldb::WriteBatch batch;
  std::vector<Id> ids;
  for (const MeshPart& part : mesh.parts) {
    if (part.parent >= int(ids.size())) return invalid_argument("mesh part '" + part.name + "' comes before its parent");
    StoredMesh m;
    VXR_ASSIGN_OR_RETURN(m.id, next_id("mesh", &batch));
    m.name = part.name;
    m.parent = part.parent < 0 ? 0 : ids[size_t(part.parent)];
    // Only the vertices this part uses, renumbered.
    std::map<uint32_t, uint32_t> remap;
    std::vector<Vec3> positions;
    std::vector<std::array<uint32_t, 3>> tris;
    for (uint32_t t = part.first_triangle; t < part.first_triangle + part.triangle_count; ++t) {
      std::array<uint32_t, 3> tri{};
      for (int k = 0; k < 3; ++k) {
        const uint32_t v = mesh.triangles.at(t)[k];
        if (v >= mesh.positions.size()) return invalid_argument("mesh triangle refers to a missing vertex");
        auto [it, fresh] = remap.try_emplace(v, uint32_t(positions.size()));
        if (fresh) positions.push_back(mesh.positions[v]);
        tri[k] = it->second;
      }
      tris.push_back(tri);
    }
    if (part.triangle_count > 0) {
      const auto& c = mesh.materials.at(mesh.triangle_material.at(part.first_triangle)).color;
      m.color = {c[0], c[1], c[2], alpha};
    } else {
      m.color[3] = alpha;
    }
    m.vertices = positions.size();
    m.triangles = tris.size();
    batch.Put(mesh_key(m.id), mesh_json(m).dump());
    batch.Put(mesh_data_key(m.id), encode_mesh_data(positions, tris));
    ids.push_back(m.id);
  }
  VXR_RETURN_IF_ERROR(write(&batch));
  return ids;
}

Result<std::vector<StoredMesh>> AnnotationStore::meshes() const {
  std::vector<StoredMesh> out;
  VXR_RETURN_IF_ERROR(scan("mesh/", [&](const std::string& k, const std::string& v) {
    auto m = decode<StoredMesh>(path_, k, v, [&](const json& j) { return mesh_from(parse_hex16(k.substr(5)), j); });
    if (!m.is_ok()) return m.status();
    out.push_back(std::move(*m));
    return Status::ok();
  }));
  return out;
}

Result<Mesh> AnnotationStore::mesh_geometry(Id id) const {
  VXR_ASSIGN_OR_RETURN(std::optional<std::string> meta, get(mesh_key(id)));
  if (!meta) return not_there("mesh", id);
  VXR_ASSIGN_OR_RETURN(StoredMesh info, decode<StoredMesh>(path_, mesh_key(id), *meta,
                                                          [&](const json& j) { return mesh_from(id, j); }));
  VXR_ASSIGN_OR_RETURN(std::optional<std::string> data, get(mesh_data_key(id)));
  const std::string damaged = path_ + ": key " + mesh_data_key(id) + ": ";
  if (!data || data->size() < 8) return corrupt(damaged + "missing or truncated; the store is damaged");
  uint32_t counts[2];
  std::memcpy(counts, data->data(), 8);
  if (counts[0] != info.vertices || counts[1] != info.triangles ||
      data->size() != 8 + uint64_t(counts[0]) * 24 + uint64_t(counts[1]) * 12)
    return corrupt(damaged + "size does not match its counts; the store is damaged");
  Mesh m;
  m.positions.resize(counts[0]);
  m.triangles.resize(counts[1]);
  if (counts[0] > 0) std::memcpy(m.positions.data(), data->data() + 8, size_t(counts[0]) * 24);
  if (counts[1] > 0) std::memcpy(m.triangles.data(), data->data() + 8 + size_t(counts[0]) * 24, size_t(counts[1]) * 12);
  for (const auto& t : m.triangles)
    for (uint32_t v : t)
      if (v >= counts[0]) return corrupt(damaged + "a triangle refers to a missing vertex; the store is damaged");
  m.materials = {{info.name, {float(info.color[0]), float(info.color[1]), float(info.color[2])}}};
  m.triangle_material.assign(m.triangles.size(), 0);
  m.parts = {{info.name, -1, 0, uint32_t(m.triangles.size())}};
  return m;
}

Status AnnotationStore::delete_mesh(Id id) {
  VXR_ASSIGN_OR_RETURN(std::vector<StoredMesh> all, meshes());
  if (std::none_of(all.begin(), all.end(), [&](const StoredMesh& m) { return m.id == id; })) return not_there("mesh", id);
  // The mesh and everything below it, in one batch.
  std::vector<Id> doomed{id};
  for (size_t i = 0; i < doomed.size(); ++i)
    for (const StoredMesh& m : all)
      if (m.parent == doomed[i]) doomed.push_back(m.id);
  leveldb::WriteBatch batch;
  for (Id d : doomed) {
    batch.Delete(mesh_key(d));
    batch.Delete(mesh_data_key(d));
  }
  return write(&batch);
}

Result<RoiContents> AnnotationStore::query(const Roi& box, std::optional<uint32_t> timepoint) const {
  RoiContents out;
  VXR_ASSIGN_OR_RETURN(std::vector<Marker> all_markers, markers());
  std::set<Id> inside;
  for (const Marker& m : all_markers) {
    if (!box.contains(m.pos)) continue;
    inside.insert(m.id);  // tracks match on position at any timepoint
    if (!timepoint || m.timepoint == *timepoint) out.markers.push_back(m);
  }
  VXR_ASSIGN_OR_RETURN(std::vector<Measurement> all_measures, measurements());
  for (const Measurement& m : all_measures)
    if (box.contains(m.a) && box.contains(m.b) && (!timepoint || m.timepoint == *timepoint))
      out.measurements.push_back(m);
  VXR_ASSIGN_OR_RETURN(std::vector<SkeletonInfo> sks, skeletons());
  for (const SkeletonInfo& info : sks) {
    VXR_ASSIGN_OR_RETURN(Skeleton sk, skeleton(info.id));
    for (const auto& [nid, n] : sk.nodes())
      if (box.contains(n.pos)) out.nodes.emplace_back(info.id, n);
  }
  VXR_ASSIGN_OR_RETURN(std::vector<Track> all_tracks, tracks());
  for (const Track& t : all_tracks)
    if (std::any_of(t.markers.begin(), t.markers.end(), [&](Id id) { return inside.count(id) > 0; }))
      out.tracks.push_back(t);
  return out;
}

// ---- cards ----

Result<Id> AnnotationStore::add_card(Card c) {
  if (!c.scene_json.empty()) {
    if (auto scene = scene_from_json(c.scene_json); !scene.is_ok()) {
      return invalid_argument("card scene: " + scene.status().message());
    }
  }
  if (!c.snapshot_png.empty() && !is_png(c.snapshot_png)) return invalid_argument("card snapshot is not a PNG file");
  if (!c.audio_wav.empty() && !is_wav(c.audio_wav)) return invalid_argument("card audio memo is not a RIFF/WAVE file");
  if (c.created_unix == 0) c.created_unix = static_cast<int64_t>(std::time(nullptr));
  leveldb::WriteBatch batch;
  VXR_ASSIGN_OR_RETURN(c.id, next_id("card", &batch));
  batch.Put(card_key(c.id), card_json(c).dump());
  // Media live under their own keys so listing and searching never read them.
  if (!c.snapshot_png.empty())
    batch.Put(blob_key(c.id, "snapshot.png"),
              leveldb::Slice(reinterpret_cast<const char*>(c.snapshot_png.data()), c.snapshot_png.size()));
  if (!c.audio_wav.empty())
    batch.Put(blob_key(c.id, "memo.wav"),
              leveldb::Slice(reinterpret_cast<const char*>(c.audio_wav.data()), c.audio_wav.size()));
  VXR_RETURN_IF_ERROR(write(&batch));
  return c.id;
}

Result<Card> AnnotationStore::card(Id id, bool with_media) const {
  VXR_ASSIGN_OR_RETURN(std::optional<std::string> v, get(card_key(id)));
  if (!v) return not_there("card", id);
  size_t snap_bytes = 0, audio_bytes = 0;
  VXR_ASSIGN_OR_RETURN(Card c, decode<Card>(path_, card_key(id), *v, [&](const json& j) {
                         Card c;
                         c.id = id;
                         c.title = j.at("title").get<std::string>();
                         c.note = j.at("note").get<std::string>();
                         c.scene_json = j.at("scene").get<std::string>();
                         c.created_unix = j.at("created").get<int64_t>();
                         c.snapshot_path = j.at("snapshot_path").get<std::string>();
                         snap_bytes = j.at("snapshot_bytes").get<size_t>();
                         audio_bytes = j.at("audio_bytes").get<size_t>();
                         return c;
                       }));
  if (!with_media) return c;
  auto load = [&](const char* what, size_t expect, std::vector<uint8_t>* out) -> Status {
    if (expect == 0) return Status::ok();
    VXR_ASSIGN_OR_RETURN(std::optional<std::string> b, get(blob_key(id, what)));
    if (!b || b->size() != expect) {
      return corrupt(path_ + ": card " + std::to_string(id) + " " + what +
                     " is missing or truncated; the store is damaged");
    }
    out->assign(b->begin(), b->end());
    return Status::ok();
  };
  VXR_RETURN_IF_ERROR(load("snapshot.png", snap_bytes, &c.snapshot_png));
  VXR_RETURN_IF_ERROR(load("memo.wav", audio_bytes, &c.audio_wav));
  return c;
}

Result<std::vector<Card>> AnnotationStore::cards() const {
  std::vector<Id> ids;
  VXR_RETURN_IF_ERROR(scan("card/", [&](const std::string& k, const std::string&) {
    ids.push_back(parse_hex16(k.substr(5)));
    return Status::ok();
  }));
  std::vector<Card> out;
  for (Id id : ids) {
    VXR_ASSIGN_OR_RETURN(Card c, card(id, false));
    out.push_back(std::move(c));
  }
  return out;
}

Status AnnotationStore::update_card_note(Id id, const std::string& title, const std::string& note) {
  VXR_ASSIGN_OR_RETURN(Card c, card(id, false));
  VXR_ASSIGN_OR_RETURN(std::optional<std::string> raw, get(card_key(id)));
  json j = json::parse(*raw, nullptr, false);  // read back above, so it parses
  j["title"] = title;
  j["note"] = note;
  leveldb::WriteBatch batch;
  batch.Put(card_key(c.id), j.dump());
  return write(&batch);
}

Status AnnotationStore::delete_card(Id id) {
  VXR_ASSIGN_OR_RETURN(Card c, card(id, false));
  leveldb::WriteBatch batch;
  batch.Delete(card_key(c.id));
  batch.Delete(blob_key(c.id, "snapshot.png"));
  batch.Delete(blob_key(c.id, "memo.wav"));
  return write(&batch);
}

Result<std::vector<Card>> AnnotationStore::search_cards(const std::string& query) const {
  std::vector<std::string> words;
  std::string cur;
  for (char ch : lower(query) + " ") {
    if (std::isalnum(static_cast<unsigned char>(ch)) || (static_cast<unsigned char>(ch) & 0x80)) {
      cur += ch;
    } else if (!cur.empty()) {
      words.push_back(cur);
      cur.clear();
    }
  }
  VXR_ASSIGN_OR_RETURN(std::vector<Card> all, cards());
  std::vector<Card> out;
  for (Card& c : all) {
    const std::string text = lower(c.title + "\n" + c.note);
    if (std::all_of(words.begin(), words.end(),
                    [&](const std::string& w) { return text.find(w) != std::string::npos; }))
      out.push_back(std::move(c));
  }
  return out;
}

}  // namespace vxr::annotate
