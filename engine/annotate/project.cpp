#include "annotate/project.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>

#include "annotate/file_io.h"

namespace vxr::annotate {

namespace fs = std::filesystem;
using nlohmann::json;

std::string project_to_json(const ProjectInfo& p) {
  const json j = {{"format", "vxr-project"},
                  {"version", p.version},
                  {"name", p.name},
                  {"description", p.description},
                  {"tags", p.tags},
                  {"created", p.created_unix},
                  {"sources", p.sources},
                  {"volume", p.volume},
                  {"annotations", p.annotations}};
  return j.dump(2) + "\n";
}

namespace {
// A member path must stay inside the project folder: a shared project must
// not make vxr read (or a catalogue link to) files elsewhere.
bool is_inner_relative(const std::string& p) {
  if (p.empty()) return false;
  const fs::path path(p);
  if (path.is_absolute()) return false;
  for (const auto& part : path.lexically_normal())
    if (part == "..") return false;
  return true;
}
}  // namespace

Result<ProjectInfo> project_from_json(const std::string& text, const std::string& origin) {
  const json j = json::parse(text, nullptr, false);
  if (j.is_discarded() || !j.is_object())
    return invalid_argument(origin + ": not a JSON object; is this a vxr project.json?");
  if (j.value("format", std::string()) != "vxr-project")
    return invalid_argument(origin + ": \"format\" is not \"vxr-project\"; this is not a vxr project file");
  ProjectInfo p;
  try {
    p.version = j.at("version").get<int>();
    if (p.version > ProjectInfo::kVersion)
      return unsupported(origin + ": project version " + std::to_string(p.version) +
                                                 " is newer than this vxr reads (version 1); open it with a newer vxr");
    if (p.version < 1) return invalid_argument(origin + ": \"version\" must be 1 or more");
    p.name = j.value("name", std::string());
    p.description = j.value("description", std::string());
    p.tags = j.value("tags", std::vector<std::string>());
    p.created_unix = j.value("created", int64_t(0));
    p.sources = j.value("sources", std::vector<std::string>());
    p.volume = j.value("volume", p.volume);
    p.annotations = j.value("annotations", p.annotations);
  } catch (const json::exception& e) {
    return invalid_argument(origin + ": a field has the wrong type (" + e.what() + ")");
  }
  if (!is_inner_relative(p.volume) || !is_inner_relative(p.annotations))
    return invalid_argument(origin + ": \"volume\" and \"annotations\" must be paths inside the project folder");
  return p;
}

std::string project_folder(const std::string& name_or_folder) {
  std::string s = name_or_folder;
  while (s.size() > 1 && s.back() == '/') s.pop_back();
  if (s.size() >= 4 && s.compare(s.size() - 4, 4, ".vxr") == 0) return s;
  return s + ".vxr";
}

Result<ProjectInfo> read_project(const std::string& folder) {
  const std::string file = (fs::path(folder) / "project.json").string();
  std::error_code ec;
  if (!fs::is_directory(folder, ec))
    return not_found(folder + ": no such project folder (make one with `vxr project create`)");
  if (!fs::exists(file, ec)) return not_found(file + ": missing; " + folder + " is not a vxr project");
  VXR_ASSIGN_OR_RETURN(std::string text, read_whole_file(file));
  return project_from_json(text, file);
}

Result<std::vector<std::string>> parse_tags(const std::string& text) {
  std::vector<std::string> tags;
  size_t start = 0;
  while (start <= text.size()) {
    size_t comma = text.find(',', start);
    if (comma == std::string::npos) comma = text.size();
    std::string t = text.substr(start, comma - start);
    t.erase(0, t.find_first_not_of(" \t"));
    t.erase(t.find_last_not_of(" \t") + 1);
    start = comma + 1;
    if (t.empty()) continue;
    for (unsigned char c : t)
      if (c < 0x20 || c == 0x7f) return invalid_argument("--tags: tag '" + t + "' holds a control character");
    if (std::find(tags.begin(), tags.end(), t) != tags.end())
      return invalid_argument("--tags: tag '" + t + "' is given twice");
    tags.push_back(t);
  }
  return tags;
}

}  // namespace vxr::annotate
