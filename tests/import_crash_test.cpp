// Crash safety of `vxr import`: the importer is SIGKILLed at many points of a
// conversion (a test hook kills it exactly when the file reaches a given byte,
// tearing the write in flight), then resumed; the result must hold the same
// chunks as an uninterrupted conversion and pass verification.
#include <doctest/doctest.h>
#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <tuple>

#include "volume/container_reader.h"
#include "volume/container_verify.h"

extern char** environ;

using namespace vxr;
namespace fs = std::filesystem;

namespace {

// Runs vxr with `args`; `env` entries are added to the environment; stdout
// goes to `stdout_path` (or nowhere). Returns the wait status.
int run_vxr(const std::vector<std::string>& args, const std::vector<std::string>& env = {},
            const std::string& stdout_path = "/dev/null") {
  std::vector<std::string> all = {VXR_CLI};
  all.insert(all.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& a : all) argv.push_back(a.data());
  argv.push_back(nullptr);
  std::vector<std::string> envs;
  for (char** e = environ; *e; ++e) envs.emplace_back(*e);
  for (const auto& e : env) envs.push_back(e);
  std::vector<char*> envp;
  for (auto& e : envs) envp.push_back(e.data());
  envp.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, stdout_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&fa, 2, "/dev/null", O_WRONLY, 0);
  pid_t pid;
  const int rc = posix_spawn(&pid, VXR_CLI, &fa, nullptr, argv.data(), envp.data());
  posix_spawn_file_actions_destroy(&fa);
  REQUIRE(rc == 0);
  int status = 0;
  waitpid(pid, &status, 0);
  return status;
}

using ChunkFacts = std::tuple<uint8_t, uint64_t, uint64_t, double, double>;  // codec, stored, checksum, min, max

std::map<std::tuple<uint32_t, uint32_t, uint32_t, uint32_t, uint32_t, uint32_t>, ChunkFacts> chunk_facts(
    const std::string& path) {
  auto r = ContainerReader::open(path);
  REQUIRE_MESSAGE(r.is_ok(), r.status().to_string());
  std::map<std::tuple<uint32_t, uint32_t, uint32_t, uint32_t, uint32_t, uint32_t>, ChunkFacts> m;
  for (uint64_t i = 0; i < (*r)->chunk_count(); ++i) {
    const vxc::IndexEntry e = (*r)->entry_at(i).value();
    m[{e.level, e.timepoint, e.channel, e.z, e.y, e.x}] = {e.codec, e.stored_size, e.payload_checksum, e.min, e.max};
  }
  return m;
}

std::string write_input(const fs::path& dir) {
  const uint64_t X = 90, Y = 70, Z = 40;
  std::vector<uint16_t> v(X * Y * Z);
  std::mt19937 rng(7);
  for (uint64_t z = 0; z < Z; ++z)
    for (uint64_t y = 0; y < Y; ++y)
      for (uint64_t x = 0; x < X; ++x)
        v[(z * Y + y) * X + x] = x < 30 ? 500 : uint16_t(1000 + x * 10 + y * 3 + z * 20 + rng() % 50);
  std::ofstream(dir / "in.raw", std::ios::binary).write(reinterpret_cast<const char*>(v.data()), v.size() * 2);
  std::ofstream(dir / "in.json") << R"({"file": "in.raw", "dims": [90, 70, 40], "dtype": "u16", "voxel_size": [1, 1, 1.5]})";
  return (dir / "in.json").string();
}

}  // namespace

TEST_CASE("crash safety: an import SIGKILLed at 26 points and resumed equals an uninterrupted one") {
  const fs::path dir = fs::temp_directory_path() / "vxr_crash_test";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string input = write_input(dir);
  const std::string ref = (dir / "ref.vxc").string();
  const int st = run_vxr({"import", input, "-o", ref, "--chunk", "16"});
  REQUIRE(WIFEXITED(st));
  REQUIRE(WEXITSTATUS(st) == 0);
  const auto want = chunk_facts(ref);
  REQUIRE(want.size() > 100);
  const uint64_t F = fs::file_size(ref);
  uint64_t index_offset = 0;
  {
    auto r = ContainerReader::open(ref);
    REQUIRE(r.is_ok());
    std::ifstream in(ref, std::ios::binary);
    vxc::Footer f;
    in.seekg(static_cast<std::streamoff>(F - sizeof f));
    in.read(reinterpret_cast<char*>(&f), sizeof f);
    index_offset = f.index_offset;
  }
  // Kill points spread over the whole file: torn header, torn chunk records
  // of every level, torn index, torn footer, and just before the rename.
  std::vector<std::pair<uint64_t, uint64_t>> points;  // (first kill, second kill or 0)
  for (uint64_t i = 0; i < 20; ++i) points.push_back({1 + (index_offset - 1) * i / 20 + 37 * i, 0});
  points.push_back({index_offset + 40, 0});
  points.push_back({F - 30, 0});
  points.push_back({F, 0});
  points.push_back({F / 4, F / 2});  // killed again while resuming
  points.push_back({F / 3, F - 10});
  points.push_back({100, F});
  int n = 0;
  for (auto [k1, k2] : points) {
    CAPTURE(k1);
    CAPTURE(k2);
    std::string out = (dir / "k").string();
    out += std::to_string(n++);
    out += ".vxc";
    int s = run_vxr({"import", input, "-o", out, "--chunk", "16"}, {"VXR_FAULT_KILL_AT_BYTE=" + std::to_string(k1)});
    REQUIRE(WIFSIGNALED(s));
    CHECK(WTERMSIG(s) == SIGKILL);
    CHECK_FALSE(fs::exists(out));  // nothing a reader could mistake for a finished file
    // Only a kill after the last byte (just before the rename) leaves a whole file behind.
    CHECK(ContainerReader::open(out + ".partial").is_ok() == (k1 >= F));
    if (k2) {
      s = run_vxr({"import", input, "-o", out, "--chunk", "16", "--resume"},
                  {"VXR_FAULT_KILL_AT_BYTE=" + std::to_string(k2)});
      REQUIRE(WIFSIGNALED(s));
      CHECK_FALSE(fs::exists(out));
    }
    s = run_vxr({"import", input, "-o", out, "--chunk", "16", "--resume"});
    REQUIRE(WIFEXITED(s));
    REQUIRE(WEXITSTATUS(s) == 0);
    CHECK_FALSE(fs::exists(out + ".partial"));
    CHECK(chunk_facts(out) == want);
    const VerifyReport rep = verify_container(out);
    CHECK(rep.ok());
    CHECK(rep.chunks_checked == want.size());
    fs::remove(out);
  }
  CHECK(n >= 20);
}

namespace {
void flip_byte(const std::string& path, uint64_t offset) {
  std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
  f.seekg(static_cast<std::streamoff>(offset));
  char c;
  f.read(&c, 1);
  c = static_cast<char>(c ^ 0x01);
  f.seekp(static_cast<std::streamoff>(offset));
  f.write(&c, 1);
}
std::string slurp(const std::string& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), {});
}
}  // namespace

TEST_CASE("corruption: `vxr verify` exits 1 and names the damage for a flipped byte in each region") {
  const fs::path dir = fs::temp_directory_path() / "vxr_verify_cli_test";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string input = write_input(dir);
  const std::string clean = (dir / "clean.vxc").string();
  int st = run_vxr({"import", input, "-o", clean, "--chunk", "32"});
  REQUIRE(WIFEXITED(st));
  REQUIRE(WEXITSTATUS(st) == 0);
  const std::string log = (dir / "verify.txt").string();
  st = run_vxr({"verify", clean}, {}, log);
  CHECK(WEXITSTATUS(st) == 0);
  CHECK(slurp(log).find("OK") != std::string::npos);

  vxc::IndexEntry victim{};
  vxc::Footer f{};
  const uint64_t F = fs::file_size(clean);
  {
    auto r = ContainerReader::open(clean);
    REQUIRE(r.is_ok());
    for (uint64_t i = 0; i < (*r)->chunk_count(); ++i)
      if (const vxc::IndexEntry e = (*r)->entry_at(i).value(); e.stored_size > 64) victim = e;
    std::ifstream in(clean, std::ios::binary);
    in.seekg(static_cast<std::streamoff>(F - sizeof f));
    in.read(reinterpret_cast<char*>(&f), sizeof f);
  }
  REQUIRE(victim.stored_size > 64);
  const std::string name = describe_key(key_of(victim));
  struct Case {
    const char* region;
    uint64_t offset;
    std::string expect;
  } cases[] = {
      {"payload", victim.offset + sizeof(vxc::RecordHeader) + victim.stored_size / 3, "BAD chunk " + name},
      {"chunk header", victim.offset + 12, "BAD chunk " + name},
      {"index", f.index_offset + sizeof(vxc::IndexHeader) + 80 + 45, "BAD index"},
      {"footer", F - 40, "BAD footer"},
  };
  for (const auto& c : cases) {
    CAPTURE(c.region);
    const std::string bad = (dir / "bad.vxc").string();
    fs::copy_file(clean, bad, fs::copy_options::overwrite_existing);
    flip_byte(bad, c.offset);
    st = run_vxr({"verify", bad}, {}, log);
    REQUIRE(WIFEXITED(st));
    CHECK(WEXITSTATUS(st) == 1);
    const std::string text = slurp(log);
    CHECK_MESSAGE(text.find(c.expect) != std::string::npos, text);
    // Reading the damaged chunk fails: either the file refuses to open or the chunk read does.
    auto r = ContainerReader::open(bad);
    if (r.is_ok()) {
      CHECK((*r)->read(key_of(victim)).status().code() == ErrorCode::kCorrupt);
    } else {
      CHECK(r.status().code() == ErrorCode::kCorrupt);
    }
  }
}
