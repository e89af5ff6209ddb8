// Runs the `vxr` binary as a user would, for tests that check exit codes,
// messages and what is left on disk.
#pragma once

#include <doctest/doctest.h>
#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

namespace vxr::test {

struct CliRun {
  int rc = -1;  // exit code; -1 when killed by a signal
  std::string out, err;
};

// A fresh, empty folder under the build's test_out/<group>/<name>.
inline std::filesystem::path scratch_dir(const std::string& group, const std::string& name) {
  const std::filesystem::path p = std::filesystem::path(VXR_TEST_OUT_DIR) / group / name;
  std::filesystem::remove_all(p);
  std::filesystem::create_directories(p);
  return p;
}

inline std::string shell_quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

// Runs `vxr <args>` (args already quoted where needed); stderr goes through a
// file in `dir`. With timeout_s > 0 the run is killed after that long (rc 124).
inline CliRun run_vxr(const std::string& args, const std::filesystem::path& dir, int timeout_s = 0) {
  const std::filesystem::path err = dir / "stderr.txt";
  const std::string prefix = timeout_s > 0 ? "timeout -s KILL " + std::to_string(timeout_s) + " " : "";
  const std::string cmd = prefix + std::string(VXR_CLI) + " " + args + " 2>" + shell_quote(err.string()) + " </dev/null";
  CliRun r;
  FILE* p = popen(cmd.c_str(), "r");
  REQUIRE(p);
  char buf[4096];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) r.out.append(buf, n);
  const int status = pclose(p);
  r.rc = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream e(err);
  r.err.assign((std::istreambuf_iterator<char>(e)), std::istreambuf_iterator<char>());
  return r;
}

inline std::string read_bytes(const std::filesystem::path& path) {
  std::ifstream f(path, std::ios::binary);
  return {(std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>()};
}

}  // namespace vxr::test
