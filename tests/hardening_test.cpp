// Outputs never touch inputs, special files are never written or waited on,
// absurd values are refused: each case reproduces a defect an adversarial run
// found (issue 12) and checks the input is byte-for-byte intact afterwards.
#include <doctest/doctest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "cli_runner.h"
#include "core/output_file.h"
#include "render/lod/brick_pool.h"
#include "volume/memory_slab_source.h"
#include "volume/pyramid_builder.h"

using namespace vxr;
using vxr::test::CliRun;
using vxr::test::read_bytes;
using vxr::test::run_vxr;
namespace fs = std::filesystem;

namespace {

const std::string kData = VXR_TESTDATA_DIR;
std::string q(const fs::path& p) { return vxr::test::shell_quote(p.string()); }

fs::path scratch(const std::string& name) { return vxr::test::scratch_dir("output_safety", name); }

// A copy of a real test file in `dir`, so a regression destroys only the copy.
fs::path copy_in(const std::string& rel, const fs::path& dir) {
  const fs::path dst = dir / fs::path(rel).filename();
  fs::copy(kData + "/" + rel, dst, fs::copy_options::recursive);
  return dst;
}

// A small .vxc made from the MRI slices.
fs::path make_container(const fs::path& dir) {
  const fs::path out = dir / "s.vxc";
  const CliRun r = run_vxr("import " + q(kData + "/tiff/mri-stack-calibrated.tif") + " -o " + q(out), dir);
  REQUIRE_MESSAGE(r.rc == 0, r.err);
  return out;
}

bool no_partial_left(const fs::path& dir) {
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.path().string().find(".partial") != std::string::npos) return false;
  return true;
}

}  // namespace

TEST_CASE("output safety: import refuses an output that is its input, and the input is intact") {
  const fs::path dir = scratch("import_self");
  const fs::path tif = copy_in("tiff/mri-stack-calibrated.tif", dir);
  const std::string before = read_bytes(tif);
  const CliRun r = run_vxr("import " + q(tif) + " -o " + q(tif), dir);
  CHECK(r.rc == 2);
  CHECK(r.err.find("is also an input") != std::string::npos);
  CHECK(read_bytes(tif) == before);
  CHECK(no_partial_left(dir));
}

TEST_CASE("output safety: import refuses an output that is one of the slices it reads") {
  const fs::path dir = scratch("import_slice");
  const fs::path slices = copy_in("slices/mri-stack", dir);
  fs::path victim;
  for (const auto& e : fs::directory_iterator(slices))
    if (victim.empty() || e.path() < victim) victim = e.path();
  const std::string before = read_bytes(victim);
  const CliRun r = run_vxr("import " + q(slices) + " -o " + q(victim), dir);
  CHECK(r.rc == 2);
  CHECK(r.err.find("is also an input") != std::string::npos);
  CHECK(read_bytes(victim) == before);
}

TEST_CASE("output safety: a multi-file OME-TIFF import refuses to overwrite a part file it reads") {
  const fs::path dir = scratch("import_ome_part");
  const fs::path set = copy_in("ome-tiff/multifile-master", dir);
  const fs::path part = set / "multifile-Z3.ome.tiff";
  const std::string before = read_bytes(part);
  const CliRun r = run_vxr("import " + q(set / "multifile-Z1.ome.tiff") + " -o " + q(part), dir);
  CHECK(r.rc == 2);
  CHECK(r.err.find("is also an input") != std::string::npos);
  CHECK(read_bytes(part) == before);
}

TEST_CASE("output safety: export-tiff and render refuse their input .vxc, also through a symlink or hard link") {
  const fs::path dir = scratch("container_self");
  const fs::path vxc = make_container(dir);
  const std::string before = read_bytes(vxc);
  fs::create_symlink(vxc, dir / "link.vxc");
  fs::create_hard_link(vxc, dir / "hard.vxc");
  for (const std::string& out : {vxc.string(), (dir / "link.vxc").string(), (dir / "hard.vxc").string()}) {
    CAPTURE(out);
    const CliRun e = run_vxr("export-tiff " + q(vxc) + " -o " + q(out), dir);
    CHECK(e.rc == 2);
    CHECK(e.err.find("is also an input") != std::string::npos);
    const CliRun r = run_vxr("render " + q(vxc) + " --size 32x32 -o " + q(out), dir);
    CHECK(r.rc == 2);
    CHECK(r.err.find("is also an input") != std::string::npos);
  }
  CHECK(read_bytes(vxc) == before);
  CHECK(fs::is_symlink(dir / "link.vxc"));
  CHECK(no_partial_left(dir));
}

TEST_CASE("output safety: render refuses to overwrite its settings file, compare refuses to overwrite an image") {
  const fs::path dir = scratch("settings_self");
  const fs::path settings = dir / "s.json";
  std::ofstream(settings) << R"({"model": "mip"})";
  const std::string before = read_bytes(settings);
  const CliRun r =
      run_vxr("render " + q(kData + "/tiff/mri-stack-calibrated.tif") + " --settings " + q(settings) + " -o " + q(settings), dir);
  CHECK(r.rc == 2);
  CHECK(read_bytes(settings) == before);
  const fs::path png = dir / "a.png";
  REQUIRE(run_vxr("render " + q(kData + "/tiff/mri-stack-calibrated.tif") + " --size 16x16 -o " + q(png), dir).rc == 0);
  const std::string png_before = read_bytes(png);
  const CliRun c = run_vxr("compare " + q(png) + " " + q(png) + " --side-by-side " + q(png), dir);
  CHECK(c.rc == 2);
  CHECK(read_bytes(png) == png_before);
}

TEST_CASE("output safety: a folder as output is refused and leaves no .partial behind") {
  const fs::path dir = scratch("output_dir");
  fs::create_directories(dir / "outdir");
  const CliRun i = run_vxr("import " + q(kData + "/tiff/mri-stack-calibrated.tif") + " -o " + q(dir / "outdir"), dir);
  CHECK(i.rc == 2);
  CHECK(i.err.find("is a folder") != std::string::npos);
  const CliRun r = run_vxr("render " + q(kData + "/tiff/mri-stack-calibrated.tif") + " -o " + q(dir / "outdir"), dir);
  CHECK(r.rc == 2);
  CHECK(no_partial_left(dir));
  CHECK(fs::is_empty(dir / "outdir"));
}

TEST_CASE("output safety: an output inside an input folder (OME-Zarr store, slice series) is refused") {
  const fs::path dir = scratch("inside_input_folder");
  const fs::path zarr = copy_in("zarr/simple_0.4", dir);
  const fs::path slices = copy_in("slices/mri-stack", dir);
  auto listing = [](const fs::path& root) {
    std::vector<std::string> names;
    for (const auto& e : fs::recursive_directory_iterator(root)) names.push_back(e.path().string());
    std::sort(names.begin(), names.end());
    return names;
  };
  const auto zarr_before = listing(zarr), slices_before = listing(slices);
  // A new file where a chunk key could be, and a new file at the store's root.
  const CliRun chunk = run_vxr("import " + q(zarr) + " -o " + q(zarr / "scale0/image/0/1"), dir);
  CHECK(chunk.rc == 2);
  CHECK(chunk.err.find("inside the input folder") != std::string::npos);
  const CliRun render = run_vxr("render " + q(zarr) + " --size 16x16 -o " + q(zarr / "view.png"), dir);
  CHECK(render.rc == 2);
  CHECK(render.err.find("inside the input folder") != std::string::npos);
  // Through a relative path with '..' that still lands inside the slice folder.
  const CliRun rel = run_vxr("import " + q(slices) + " -o " + q(slices / ".." / "mri-stack" / "x.vxc"), dir);
  CHECK(rel.rc == 2);
  CHECK(rel.err.find("inside the input folder") != std::string::npos);
  CHECK(listing(zarr) == zarr_before);
  CHECK(listing(slices) == slices_before);
  // Beside the folder is fine.
  CHECK(run_vxr("render " + q(zarr) + " --size 16x16 -o " + q(dir / "view.png"), dir).rc == 0);
}

TEST_CASE("output safety: a FIFO as output is refused and stays a FIFO") {
  const fs::path dir = scratch("output_fifo");
  const fs::path fifo = dir / "out.png";
  REQUIRE(::mkfifo(fifo.c_str(), 0644) == 0);
  const CliRun r = run_vxr("render " + q(kData + "/tiff/mri-stack-calibrated.tif") + " -o " + q(fifo), dir, 60);
  CHECK(r.rc == 2);
  CHECK(r.err.find("FIFO") != std::string::npos);
  CHECK(fs::is_fifo(fifo));
  const CliRun e = run_vxr("export-tiff " + q(make_container(dir)) + " -o " + q(fifo), dir, 60);
  CHECK(e.rc == 2);
  CHECK(fs::is_fifo(fifo));
}

TEST_CASE("output safety: a FIFO as input fails at once instead of waiting for a writer") {
  const fs::path dir = scratch("input_fifo");
  const fs::path tif = dir / "in.tif", vxc = dir / "in.vxc", png = dir / "in.png";
  for (const fs::path& f : {tif, vxc, png}) REQUIRE(::mkfifo(f.c_str(), 0644) == 0);
  const CliRun i = run_vxr("import " + q(tif) + " -o " + q(dir / "o.vxc"), dir, 30);
  CHECK(i.rc == 1);
  CHECK(i.err.find("FIFO") != std::string::npos);
  const CliRun v = run_vxr("info " + q(vxc), dir, 30);
  CHECK(v.rc == 1);
  CHECK(v.err.find("not a regular file") != std::string::npos);
  const CliRun r = run_vxr("render " + q(vxc) + " -o " + q(dir / "o.png"), dir, 30);
  CHECK(r.rc == 1);
  const CliRun c = run_vxr("compare " + q(png) + " " + q(png), dir, 30);
  CHECK(c.rc == 1);
  CHECK(!fs::exists(dir / "o.vxc"));
  CHECK(!fs::exists(dir / "o.png"));
}

TEST_CASE("output safety: planted symlinks at temp names are never written through") {
  const fs::path dir = scratch("planted_symlink");
  const fs::path victim = dir / "victim.txt";
  std::ofstream(victim) << "precious";
  // The container writer's resumable temp name is fixed: a link there is refused, with and without --resume.
  fs::create_symlink(victim, dir / "out.vxc.partial");
  const std::string tif = kData + "/tiff/mri-stack-calibrated.tif";
  CHECK(run_vxr("import " + q(tif) + " -o " + q(dir / "out.vxc"), dir).rc != 0);
  const CliRun r = run_vxr("import " + q(tif) + " -o " + q(dir / "out.vxc") + " --resume", dir);
  CHECK(r.rc != 0);
  CHECK(r.err.find("symbolic link") != std::string::npos);
  // PNG and TIFF temp names are fresh O_EXCL names: the old fixed name is simply not used.
  fs::create_symlink(victim, dir / "out.png.partial");
  CHECK(run_vxr("render " + q(tif) + " --size 16x16 -o " + q(dir / "out.png"), dir).rc == 0);
  CHECK(read_bytes(victim) == "precious");
  CHECK(fs::is_symlink(dir / "out.png.partial"));
  // Annotation exports (SWC, CSV, card files) used a fixed "<out>.partial" too.
  const fs::path store = dir / "store";
  REQUIRE(run_vxr("annotate init " + q(store), dir).rc == 0);
  REQUIRE(run_vxr("annotate add-marker " + q(store) + " --pos 1,2,3", dir).rc == 0);
  fs::create_symlink(victim, dir / "points.csv.partial");
  CHECK(run_vxr("annotate export-csv " + q(store) + " --what points -o " + q(dir / "points.csv"), dir).rc == 0);
  CHECK(read_bytes(victim) == "precious");
  CHECK(read_bytes(dir / "points.csv").find("1,2,3") != std::string::npos);
}

TEST_CASE("output safety: TempFile commits all or nothing and refuses a target that became a folder") {
  const fs::path dir = scratch("tempfile");
  const fs::path target = dir / "t.txt";
  {
    auto t = TempFile::create_beside(target.string());
    REQUIRE(t.is_ok());
    REQUIRE(t->write("abc").is_ok());
    CHECK(!fs::exists(target));  // nothing under the final name until commit
  }
  CHECK(!fs::exists(target));
  CHECK(fs::is_empty(dir));  // an abandoned temp file is removed
  auto t = TempFile::create_beside(target.string());
  REQUIRE(t.is_ok());
  REQUIRE(t->write("abc").is_ok());
  fs::create_directory(target);
  CHECK(!t->commit().is_ok());
  CHECK(fs::is_directory(target));
  fs::remove(target);
  REQUIRE(write_file_atomically(target.string(), std::string("xyz")).is_ok());
  CHECK(read_bytes(target) == "xyz");
}

TEST_CASE("limits: absurd command-line values are usage errors, not hangs") {
  const fs::path dir = scratch("limits");
  const std::string tif = kData + "/tiff/mri-stack-calibrated.tif";
  CHECK(run_vxr("view --sample --headless --frames -1", dir, 60).rc == 2);
  const CliRun ref = run_vxr("render " + q(tif) + " --reference --reference-step 1e-9 -o " + q(dir / "r.png"), dir, 60);
  CHECK(ref.rc == 2);
  CHECK(ref.err.find("--reference-step") != std::string::npos);
  for (const std::string fov : {"0", "-5", "200"}) {
    const fs::path scene = dir / "scene.json";
    std::ofstream(scene) << R"({"camera": {"eye": [0, 0, 300], "target": [0, 0, 0], "up": [0, 1, 0], "fov_y_deg": )"
                         << fov << "}}";
    const CliRun r = run_vxr("render " + q(tif) + " --settings " + q(scene) + " -o " + q(dir / "f.png"), dir, 60);
    CAPTURE(fov);
    CHECK(r.rc == 2);
    CHECK(r.err.find("fov_y_deg") != std::string::npos);
  }
  const CliRun unit = run_vxr("import " + q(tif) + " -o " + q(dir / "u.vxc") + " --unit \"$(printf '\\377\\376')\"", dir);
  CHECK(unit.rc == 2);
  CHECK(unit.err.find("--unit") != std::string::npos);
  CHECK(!fs::exists(dir / "u.vxc"));
}

TEST_CASE("limits: a voxel size no renderer can draw is refused at import, with the fix in the message") {
  const fs::path dir = scratch("voxel_size");
  std::vector<uint8_t> voxels(8 * 8 * 8, 7);
  std::ofstream(dir / "v.raw", std::ios::binary).write(reinterpret_cast<const char*>(voxels.data()), voxels.size());
  std::ofstream(dir / "v.json") << R"({"dims": [8, 8, 8], "dtype": "u8", "file": "v.raw", "voxel_size": [1e-9, 1, 1e9]})";
  const CliRun r = run_vxr("import " + q(dir / "v.json") + " -o " + q(dir / "v.vxc"), dir);
  CHECK(r.rc == 1);
  CHECK(r.err.find("v.json") != std::string::npos);
  CHECK(r.err.find("--voxel-size") != std::string::npos);
  CHECK(run_vxr("import " + q(dir / "v.json") + " -o " + q(dir / "v.vxc") + " --voxel-size 1,1,2", dir).rc == 0);
}

TEST_CASE("limits: `vxr info --json` prints valid JSON for a container whose unit is not UTF-8") {
  const fs::path dir = scratch("unit_utf8");
  VolumeInfo info;
  info.dims = {16, 16, 16};
  info.dtype = DType::kU8;
  info.unit = "\xff\xfe";
  MemorySlabSource src(info, {std::vector<uint8_t>(16 * 16 * 16, 3)});
  ImportOptions opt;
  opt.chunk_size = 16;
  REQUIRE(build_container(src, (dir / "u.vxc").string(), opt).is_ok());
  const CliRun r = run_vxr("info --json " + q(dir / "u.vxc"), dir);
  CHECK(r.rc == 0);
  const auto j = nlohmann::json::parse(r.out, nullptr, false);
  CHECK(!j.is_discarded());
}

TEST_CASE("limits: fit_slots lowers the atlas to the device instead of refusing wide chunks") {
  // 128^3 chunks + apron: the default 16x16x8 wants 2080 texels a side, within 4096, but 2.2 GiB: shrunk to fit.
  auto s = fit_slots({16, 16, 8}, 130, 1, 4096, kMaxAtlasBytes);
  REQUIRE(s.is_ok());
  CHECK(uint64_t(s->x) * s->y * s->z * 130 * 130 * 130 <= kMaxAtlasBytes);
  CHECK(s->x * 130 <= 4096);
  // 512^3 chunks of u16: 7 axis slots would fit 4096 texels, but only 7 bricks fit the heap.
  auto w = fit_slots({16, 16, 8}, 514, 2, 4096, kMaxAtlasBytes);
  REQUIRE(w.is_ok());
  const uint64_t n = uint64_t(w->x) * w->y * w->z;
  CHECK(n >= 1);
  CHECK(n * 514ull * 514 * 514 * 2 <= kMaxAtlasBytes);
  CHECK((n + 1) * 514ull * 514 * 514 * 2 > kMaxAtlasBytes / 2);  // not shrunk needlessly far
  CHECK(!fit_slots({1, 1, 1}, 5000, 1, 4096, kMaxAtlasBytes).is_ok());
}

TEST_CASE("limits: a container with 512-voxel chunks renders through the out-of-core renderer") {
  const fs::path dir = scratch("wide_chunks");
  const CliRun i = run_vxr("import " + q(kData + "/tiff/mri-stack-calibrated.tif") + " --chunk 512 -o " + q(dir / "w.vxc"), dir);
  REQUIRE_MESSAGE(i.rc == 0, i.err);
  const CliRun r = run_vxr("render " + q(dir / "w.vxc") + " --size 64x64 -o " + q(dir / "w.png"), dir, 300);
  CHECK_MESSAGE(r.rc == 0, r.err);
  CHECK(fs::exists(dir / "w.png"));
}
