// Flags `vxr render` and `vxr view` share, registered and parsed here once so
// both commands read them the same way.
#include <cstdlib>

#include "annotate/annotation_store.h"
#include "command.h"

namespace vxr::cli {

void add_annotations_option(CLI::App* cmd, std::string& store) {
  cmd->add_option("--annotations", store,
                  "annotation store (vxr annotate) whose markers, skeletons and meshes are drawn with the volume; "
                  "a project folder NAME.vxr given as the input draws its own store");
}

Result<Scene> load_card_scene(const std::string& spec, const std::string& default_store) {
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

}  // namespace vxr::cli
