#include "render/card_scene.h"

#include <cstdlib>
#include <filesystem>

#include "annotate/annotation_store.h"
#include "annotate/project.h"

namespace vxr {

Result<Scene> load_card_scene(const std::string& spec, const std::string& annotations_flag, const std::string& input) {
  std::string default_store = annotations_flag;
  std::error_code ec;
  if (default_store.empty() && !input.empty() && std::filesystem::exists(std::filesystem::path(input) / "project.json", ec)) {
    VXR_ASSIGN_OR_RETURN(annotate::ProjectInfo project, annotate::read_project(input));
    default_store = (std::filesystem::path(input) / project.annotations).string();
  }
  // "STORE:ID" (the store path may itself hold colons: the id follows the last), or "ID" with a default store.
  const size_t colon = spec.rfind(':');
  const std::string id_text = colon == std::string::npos ? spec : spec.substr(colon + 1);
  const std::string store_path = colon == std::string::npos ? default_store : spec.substr(0, colon);
  char* end = nullptr;
  const unsigned long long id = std::strtoull(id_text.c_str(), &end, 10);
  if (store_path.empty() || id_text.empty() || *end != '\0' || id == 0)
    return invalid_argument("--card '" + spec + "': give STORE:ID, e.g. brain.vxr/annotations:3" +
                            (default_store.empty() ? "" : ", or ID for a card of " + default_store));
  VXR_ASSIGN_OR_RETURN(auto store, annotate::AnnotationStore::open(store_path, /*create=*/false));
  VXR_ASSIGN_OR_RETURN(annotate::Card card, store->card(id, /*with_media=*/false));
  if (card.scene_json.empty())
    return invalid_argument(store_path + ": card " + id_text + " was stored without a scene; there is no view to restore");
  auto scene = scene_from_json(card.scene_json);
  if (!scene) return invalid_argument(store_path + ": card " + id_text + ": " + scene.status().message());
  return scene;
}

Camera scene_world_camera(const Scene& sc, const VolumePlacement& placement, bool flat) {
  Camera camera = flat ? orbit_camera(placement, 0.0, 90.0 - 1e-3, 1.1) : orbit_camera(placement, 30.0, 25.0, 1.25);
  if (sc.has_camera) {
    camera.eye = {sc.camera.eye[0], sc.camera.eye[1], sc.camera.eye[2]};
    camera.target = {sc.camera.target[0], sc.camera.target[1], sc.camera.target[2]};
    camera.up = {sc.camera.up[0], sc.camera.up[1], sc.camera.up[2]};
    camera.fov_y_deg = sc.camera.fov_y_deg;
  }
  return camera;
}

Camera scene_camera(const Scene& sc, const VolumePlacement& placement, bool flat) {
  return camera_in_volume_frame(scene_world_camera(sc, placement, flat), sc.transform);
}

Camera camera_in_volume_frame(const Camera& world, const VolumeTransform& transform) {
  if (transform == VolumeTransform{}) return world;
  const CameraState in{{world.eye.x, world.eye.y, world.eye.z},
                       {world.target.x, world.target.y, world.target.z},
                       {world.up.x, world.up.y, world.up.z},
                       world.fov_y_deg};
  const CameraState v = camera_in_volume_frame(in, transform);
  Camera camera = world;
  camera.eye = {v.eye[0], v.eye[1], v.eye[2]};
  camera.target = {v.target[0], v.target[1], v.target[2]};
  camera.up = {v.up[0], v.up[1], v.up[2]};
  return camera;
}

}  // namespace vxr
