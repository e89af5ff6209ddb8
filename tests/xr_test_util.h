// Helpers for the XR tests: pointing the Khronos loader at the test runtime
// with core validation in front, writing scripts, running `vxr` as a child.
#pragma once

#include <sys/wait.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

namespace vxr::test {

inline std::string xr_out_dir(const std::string& name) {
  const std::filesystem::path p = std::filesystem::path(VXR_TEST_OUT_DIR) / "xr" / name;
  std::filesystem::remove_all(p);
  std::filesystem::create_directories(p);
  return p.string();
}

// Environment for the test runtime, core validation writing to `dir`/core_validation.txt.
inline void use_test_runtime(const std::string& dir, const std::string& script_json) {
  const std::string script = dir + "/script.json";
  std::ofstream(script) << script_json;
  setenv("XR_RUNTIME_JSON", VXR_TEST_RUNTIME_JSON, 1);
  setenv("XR_ENABLE_API_LAYERS", "XR_APILAYER_LUNARG_core_validation", 1);
  setenv("XR_CORE_VALIDATION_EXPORT_TYPE", "text", 1);
  setenv("XR_CORE_VALIDATION_FILE_NAME", (dir + "/core_validation.txt").c_str(), 1);
  setenv("VXR_TEST_RUNTIME_SCRIPT", script.c_str(), 1);
  setenv("VXR_TEST_RUNTIME_REPORT", (dir + "/report.json").c_str(), 1);
  setenv("VXR_TEST_RUNTIME_DUMP_DIR", (dir + "/dump").c_str(), 1);
}

inline std::string read_text(const std::string& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// What core validation wrote (empty when it reported nothing).
inline std::string core_validation_messages(const std::string& dir) {
  const std::string text = read_text(dir + "/core_validation.txt");
  return text.find("VALID_ERROR") != std::string::npos || text.find("VALID_WARNING") != std::string::npos ? text : "";
}

inline nlohmann::json runtime_report(const std::string& dir) {
  std::ifstream in(dir + "/report.json");
  if (!in) return nlohmann::json::array();
  return nlohmann::json::parse(in, nullptr, false);
}

struct ChildResult {
  int exit_code = -1;  // -1: killed by a signal (a crash)
  int signal = 0;
  std::string output;  // stdout and stderr
};

// Runs `command` through the shell, capturing stdout and stderr.
// A command prefix giving a viewer its own config folder under `dir` (window
// size, remembered views per dataset), so tests neither read the user's nor
// each other's.
inline std::string own_config(const std::string& dir) {
  return "XDG_CONFIG_HOME=" + (std::filesystem::path(dir) / "config").string() + " ";
}

inline ChildResult run_child(const std::string& command) {
  ChildResult r;
  FILE* p = popen((command + " 2>&1").c_str(), "r");
  if (!p) return r;
  char buf[4096];
  size_t n;
  while ((n = fread(buf, 1, sizeof buf, p)) > 0) r.output.append(buf, n);
  const int status = pclose(p);
  if (WIFEXITED(status)) r.exit_code = WEXITSTATUS(status);
  if (WIFSIGNALED(status)) r.signal = WTERMSIG(status);
  return r;
}

}  // namespace vxr::test
