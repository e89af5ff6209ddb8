// A project: one folder NAME.vxr/ holding the imported volume, the annotation
// store and project.json (the description below). `vxr project create` makes
// it, `vxr project pack` zips it, `vxr catalog` reads it. docs/annotation-store.md
// documents project.json for other tools.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/status.h"

namespace vxr::annotate {

struct ProjectInfo {
  static constexpr int kVersion = 1;
  int version = kVersion;
  std::string name;                  // NAME, without the .vxr suffix
  std::string description;
  std::vector<std::string> tags;
  int64_t created_unix = 0;          // seconds since 1970, UTC
  std::vector<std::string> sources;  // the raw files imported, absolute paths at creation
  std::string volume = "volume.vxc";        // relative to the project folder
  std::string annotations = "annotations";  // relative to the project folder
  bool operator==(const ProjectInfo&) const = default;
};

std::string project_to_json(const ProjectInfo& p);
// Errors name `origin` (the file) and the field.
Result<ProjectInfo> project_from_json(const std::string& text, const std::string& origin);

// "brain" or "brain.vxr" or "out/brain.vxr" -> "out/brain.vxr".
std::string project_folder(const std::string& name_or_folder);
// Reads <folder>/project.json; refuses a newer version and paths that leave the folder.
Result<ProjectInfo> read_project(const std::string& folder);

// "a, b,,c" -> {"a", "b", "c"}; kInvalidArgument on a repeated tag or a control character.
Result<std::vector<std::string>> parse_tags(const std::string& text);

}  // namespace vxr::annotate
