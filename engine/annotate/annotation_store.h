// AnnotationStore: one LevelDB database per project holding every annotation
// (markers, measurements, skeletons, tracks, ROIs, cards). Key schema and
// value encoding: docs/annotation-store.md. Every mutation is one WriteBatch
// written with sync, so an edit is either wholly on disk when the call
// returns or not there at all, even if the process is killed. Opened with
// paranoid_checks, read with verify_checksums. One process at a time: LevelDB
// locks the folder, and a second open fails with a message saying so.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "annotate/annotations.h"
#include "annotate/obj.h"
#include "annotate/skeleton.h"
#include "core/status.h"

namespace leveldb {
class DB;
class WriteBatch;
}  // namespace leveldb

namespace vxr::annotate {

// What lies inside a box (AnnotationStore::query).
struct RoiContents {
  std::vector<Marker> markers;
  std::vector<Measurement> measurements;           // both end points inside
  std::vector<std::pair<Id, SkeletonNode>> nodes;  // (skeleton id, node)
  std::vector<Track> tracks;                       // at least one marker inside
};

struct SkeletonInfo {
  Id id = 0;
  std::string name;
};

class AnnotationStore {
 public:
  static constexpr int kSchemaVersion = 1;

  // Opens the store in folder `path`. create_if_missing makes a new, empty
  // store (schema version written); otherwise a missing store is kNotFound.
  // A store written by a newer schema is refused (kUnsupported) with both
  // version numbers; a LevelDB folder that is not a vxr store is kCorrupt.
  static Result<std::unique_ptr<AnnotationStore>> open(const std::string& path, bool create_if_missing);
  ~AnnotationStore();
  AnnotationStore(const AnnotationStore&) = delete;
  AnnotationStore& operator=(const AnnotationStore&) = delete;

  const std::string& path() const { return path_; }

  // Voxel size and unit used for metric lengths (default 1 um isotropic).
  const VoxelSpace& voxel_space() const { return space_; }
  Status set_voxel_space(const VoxelSpace& space);

  // Markers (counting, feature tracking). add_* ignores the given id and returns the new one.
  Result<Id> add_marker(Marker marker);
  Status update_marker(const Marker& marker);
  Status delete_marker(Id id);  // also leaves any track holding it
  Result<Marker> marker(Id id) const;
  Result<std::vector<Marker>> markers() const;
  // Markers per class, optionally only those at `timepoint`.
  Result<std::map<std::string, size_t>> counts(std::optional<uint32_t> timepoint = std::nullopt) const;

  Result<Id> add_measurement(Measurement m);
  Status delete_measurement(Id id);
  Result<Measurement> measurement(Id id) const;
  Result<std::vector<Measurement>> measurements() const;
  // Metric length in voxel_space().unit.
  double length(const Measurement& m) const { return space_.distance(m.a, m.b); }

  // Skeletons. add_skeleton validates the tree and stores it whole.
  Result<Id> add_skeleton(const Skeleton& skeleton);
  Result<Skeleton> skeleton(Id id) const;
  Result<std::vector<SkeletonInfo>> skeletons() const;
  Status delete_skeleton(Id id);
  // Loads the skeleton, applies `edit`, checks the tree is still valid and
  // writes only the nodes that changed, atomically. A failed edit or an
  // invalid result writes nothing.
  Status edit_skeleton(Id id, const std::function<Status(Skeleton&)>& edit);
  Result<int64_t> add_node(Id skeleton, SkeletonNode node);
  Status move_node(Id skeleton, int64_t node, const Vec3& pos);
  Status delete_node(Id skeleton, int64_t node);
  Status reparent_node(Id skeleton, int64_t node, int64_t new_parent);
  // Moves the subtree at `node` into a new skeleton; returns its id.
  Result<Id> split_skeleton(Id skeleton, int64_t node);
  // Moves `source` (re-rooted at source_node) under `attach_to` in `target`
  // and deletes `source`; returns source's old node id -> new id in target.
  Result<std::map<int64_t, int64_t>> merge_skeletons(Id target, int64_t attach_to, Id source, int64_t source_node);

  // Tracks: a feature's markers across timepoints, one per timepoint.
  Result<Id> add_track(const std::string& name, const std::vector<Id>& markers);
  Status add_to_track(Id track, Id marker);
  // Deletes the track and its markers (they were placed for it), in one batch.
  Status delete_track(Id id);
  Result<Track> track(Id id) const;
  Result<std::vector<Track>> tracks() const;

  Result<Id> add_roi(Roi roi);
  Result<Roi> roi(Id id) const;
  Result<std::vector<Roi>> rois() const;
  Status delete_roi(Id id);
  // The annotations inside `box`; with `timepoint`, markers and measurements
  // at other timepoints are left out.
  // Meshes: every part of `mesh` (positions in volume coordinates) becomes
  // one StoredMesh, parents before children, in one batch; returns their ids
  // in part order. Its colour is its first triangle's material.
  Result<std::vector<Id>> add_meshes(const Mesh& mesh, double alpha = 1.0);
  Result<std::vector<StoredMesh>> meshes() const;
  // One stored part's triangles (only its own, not its children's).
  Result<Mesh> mesh_geometry(Id id) const;
  // Deletes the mesh and every mesh below it.
  Status delete_mesh(Id id);

  Result<RoiContents> query(const Roi& box, std::optional<uint32_t> timepoint = std::nullopt) const;

  // Cards. scene_json must parse as a Scene; snapshot bytes must be a PNG and
  // audio a RIFF/WAVE file. created_unix 0 means "now".
  Result<Id> add_card(Card card);
  Status update_card_note(Id id, const std::string& title, const std::string& note);
  Status delete_card(Id id);
  // with_media false leaves snapshot_png and audio_wav empty (listing is cheap).
  Result<Card> card(Id id, bool with_media = true) const;
  Result<std::vector<Card>> cards() const;  // no media
  // Cards whose title or note contains every word of `query` (case-insensitive).
  Result<std::vector<Card>> search_cards(const std::string& query) const;

 private:
  AnnotationStore(std::string path, leveldb::DB* db) : path_(std::move(path)), db_(db) {}
  Status init();
  Result<Id> next_id(const std::string& kind, leveldb::WriteBatch* batch);
  Status write(leveldb::WriteBatch* batch);
  Result<std::optional<std::string>> get(const std::string& key) const;
  Status scan(const std::string& prefix,
              const std::function<Status(const std::string& key, const std::string& value)>& fn) const;
  Status write_skeleton_diff(const Skeleton& before, const Skeleton& after, leveldb::WriteBatch* batch);
  Status check_track_markers(const std::vector<Id>& ids, std::vector<Id>* sorted) const;
  Status not_there(const std::string& kind, Id id) const;

  std::string path_;
  leveldb::DB* db_ = nullptr;  // owned; deleted in the destructor
  VoxelSpace space_;
  std::map<std::string, Id> next_;  // id counters, mirrored from meta/next/<kind>
};

}  // namespace vxr::annotate
