// `vxr project create NAME --from FILES...` and `vxr project pack NAME`: a
// project folder NAME.vxr/ (engine/annotate/project.h) holding the imported
// volume, the annotation store and project.json, and its zip for sharing.
#include <archive.h>
#include <archive_entry.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>

#include "annotate/annotation_store.h"
#include "annotate/project.h"
#include "command.h"
#include "core/output_file.h"
#include "volume/open_chunk_source.h"

namespace vxr::cli {

using namespace vxr::annotate;
namespace fs = std::filesystem;

namespace {

struct CreateArgs {
  std::string name, tags, description, voxel_size, unit;
  std::vector<std::string> from;
};

// The annotation store measures in um, nm or mm; other units keep its default.
void seed_voxel_space(AnnotationStore& store, const std::string& volume) {
  auto src = open_chunk_source(volume);
  if (!src) return;
  const VolumeInfo& info = src->source->info();
  if (info.unit != "um" && info.unit != "nm" && info.unit != "mm") {
    std::fprintf(stderr, "vxr: note: the volume's unit '%s' is not um, nm or mm; annotation lengths are in voxels "
                 "until `vxr annotate init STORE --voxel-size X,Y,Z --unit um` sets one\n", info.unit.c_str());
    return;
  }
  VoxelSpace vs;
  vs.voxel_size = {info.voxel_size[0], info.voxel_size[1], info.voxel_size[2]};
  vs.unit = info.unit;
  if (Status st = store.set_voxel_space(vs); !st.is_ok())
    std::fprintf(stderr, "vxr: note: %s\n", st.message().c_str());
}

int run_create(const CreateArgs& a) {
  const std::string folder = project_folder(a.name);
  const std::string name = fs::path(folder).stem().string();
  if (name.empty() || name == "." || name == "..")
    return fail(invalid_argument("project name '" + a.name + "': give a name such as brain or out/brain"), kExitUsage);
  auto tags = parse_tags(a.tags);
  if (!tags) return fail(tags.status(), kExitUsage);
  std::error_code ec;
  if (fs::exists(fs::symlink_status(folder, ec)))
    return fail(invalid_argument(folder + ": already exists; choose another name or remove it first"), kExitUsage);
  const fs::path parent = fs::absolute(folder, ec).parent_path();
  if (!fs::is_directory(parent, ec))
    return fail(invalid_argument(folder + ": the folder " + parent.string() + " does not exist"), kExitUsage);
  for (const std::string& in : a.from) {
    const fs::path abs = fs::weakly_canonical(in, ec);
    const fs::path target = fs::weakly_canonical(folder, ec);
    if (abs == target || abs.string().rfind(target.string() + "/", 0) == 0)
      return fail(invalid_argument(in + ": an input inside the project folder " + folder), kExitUsage);
  }

  // Built in a hidden folder beside the target and renamed when complete: a
  // failed import leaves no half project under the name.
  std::string tmpl = (parent / ("." + name + ".vxr.XXXXXX")).string();
  if (!mkdtemp(tmpl.data()))
    return fail(io_error(parent.string() + ": cannot create a folder there (" + std::strerror(errno) + ")"));
  const fs::path work = tmpl;
  auto cleanup = [&] { fs::remove_all(work, ec); };

  ProjectInfo p;
  p.name = name;
  p.description = a.description;
  p.tags = *tags;
  p.created_unix = static_cast<int64_t>(std::time(nullptr));
  for (const std::string& in : a.from) p.sources.push_back(fs::absolute(in, ec).lexically_normal().string());
  const std::string volume = (work / p.volume).string();
  if (int rc = import_volume(a.from, volume, a.voxel_size, a.unit); rc != kExitOk) {
    cleanup();
    return rc;
  }
  {
    auto store = AnnotationStore::open((work / p.annotations).string(), /*create=*/true);
    if (!store) {
      cleanup();
      return fail(store.status());
    }
    seed_voxel_space(**store, volume);
  }  // closed (unlocked) before the rename
  if (Status st = write_file_atomically((work / "project.json").string(), project_to_json(p)); !st) {
    cleanup();
    return fail(st);
  }
  if (std::rename(work.c_str(), folder.c_str()) != 0) {
    const int e = errno;
    cleanup();
    return fail(io_error(folder + ": cannot move the finished project into place (" + std::strerror(e) + ")"));
  }
  std::printf("%s: project '%s', %zu tag(s), volume %s, annotations %s\n", folder.c_str(), name.c_str(), p.tags.size(),
              p.volume.c_str(), p.annotations.c_str());
  return kExitOk;
}

// Every regular file under `root` (sorted, so archives are reproducible);
// symlinks are refused: a shared archive must not carry links out of the project.
Result<std::vector<fs::path>> project_files(const fs::path& root) {
  std::vector<fs::path> files;
  std::error_code ec;
  for (auto it = fs::recursive_directory_iterator(root, ec); !ec && it != fs::recursive_directory_iterator();
       it.increment(ec)) {
    const auto st = it->symlink_status(ec);
    if (fs::is_symlink(st)) return invalid_argument(it->path().string() + ": a symbolic link; projects hold plain files only");
    if (fs::is_regular_file(st)) files.push_back(it->path());
  }
  if (ec) return io_error(root.string() + ": cannot list the folder (" + ec.message() + ")");
  std::sort(files.begin(), files.end());
  return files;
}

int run_pack(const std::string& name, std::string out) {
  const std::string folder = project_folder(name);
  auto info = read_project(folder);
  if (!info) return fail(info.status(), info.status().code() == ErrorCode::kNotFound ? kExitUsage : kExitFailure);
  if (out.empty()) out = folder + ".zip";
  auto files = project_files(folder);
  if (!files) return fail(files.status());
  std::vector<std::string> inputs;
  for (const fs::path& f : *files) inputs.push_back(f.string());
  if (Status st = check_output(out, inputs, "-o"); !st) return fail(st, kExitUsage);
  std::error_code ec;
  const fs::path o = fs::weakly_canonical(out, ec), root = fs::weakly_canonical(folder, ec);
  if (o.string().rfind(root.string() + "/", 0) == 0)
    return fail(invalid_argument("-o " + out + ": inside the project being packed; write it elsewhere"), kExitUsage);

  auto tmp = TempFile::create_beside(out);
  if (!tmp) return fail(tmp.status());
  archive* a = archive_write_new();
  auto zip_error = [&](const std::string& what) {
    const std::string msg = out + ": " + what + " (" + (archive_error_string(a) ? archive_error_string(a) : "zip error") + ")";
    archive_write_free(a);
    return fail(io_error(msg));
  };
  if (archive_write_set_format_zip(a) != ARCHIVE_OK || archive_write_open_fd(a, tmp->fd()) != ARCHIVE_OK)
    return zip_error("cannot start the zip");
  const std::string top = fs::path(folder).filename().string();  // entries unpack into NAME.vxr/
  std::vector<char> buf(1 << 20);
  for (const fs::path& f : *files) {
    const std::string rel = fs::relative(f, folder, ec).generic_string();
    struct stat st {};
    const int fd = ::open(f.c_str(), O_RDONLY | O_NOFOLLOW | O_CLOEXEC);
    if (fd < 0 || fstat(fd, &st) != 0) {
      if (fd >= 0) ::close(fd);
      archive_write_free(a);
      return fail(io_error(f.string() + ": cannot read it (" + std::strerror(errno) + ")"));
    }
    // The volume's chunks are LZ4 already: storing them is as small and much faster.
    if (rel == info->volume) archive_write_zip_set_compression_store(a);
    else archive_write_zip_set_compression_deflate(a);
    archive_entry* e = archive_entry_new();
    archive_entry_set_pathname(e, (top + "/" + rel).c_str());
    archive_entry_set_filetype(e, AE_IFREG);
    archive_entry_set_perm(e, 0644);
    archive_entry_set_size(e, st.st_size);
    archive_entry_set_mtime(e, st.st_mtime, 0);
    bool ok = archive_write_header(a, e) == ARCHIVE_OK;
    archive_entry_free(e);
    int64_t left = st.st_size;
    while (ok && left > 0) {
      const ssize_t n = ::read(fd, buf.data(), std::min<int64_t>(left, buf.size()));
      if (n <= 0) break;
      ok = archive_write_data(a, buf.data(), size_t(n)) == n;
      left -= n;
    }
    ::close(fd);
    if (!ok) return zip_error("cannot add " + rel);
    if (left != 0) {
      archive_write_free(a);
      return fail(io_error(f.string() + ": changed size while being packed; close what writes to it and pack again"));
    }
  }
  if (archive_write_close(a) != ARCHIVE_OK) return zip_error("cannot finish the zip");
  archive_write_free(a);
  if (Status st = tmp->commit(); !st) return fail(st);
  std::printf("%s: %zu files of project '%s'\n", out.c_str(), files->size(), info->name.c_str());
  return kExitOk;
}

}  // namespace

void add_project_command(CLI::App& app, Invocation& inv) {
  auto* top = app.add_subcommand("project", "a project folder NAME.vxr: volume, annotation store, project.json");
  top->require_subcommand(1);
  {
    auto a = std::make_shared<CreateArgs>();
    auto* cmd = top->add_subcommand("create", "import raw files into a new project NAME.vxr/");
    cmd->add_option("name", a->name, "project name (NAME or DIR/NAME; the folder is NAME.vxr)")->required();
    cmd->add_option("--from", a->from, "the image files to import (as `vxr import`)")->required();
    cmd->add_option("--tags", a->tags, "comma-separated tags, e.g. mouse,cortex");
    cmd->add_option("--description", a->description, "a line of text about the project");
    cmd->add_option("--voxel-size", a->voxel_size, "voxel size x,y,z (overrides the file's)");
    cmd->add_option("--unit", a->unit, "unit of the voxel size, e.g. um");
    cmd->callback([&inv, a] { inv.run = [a] { return run_create(*a); }; });
  }
  {
    auto name = std::make_shared<std::string>();
    auto out = std::make_shared<std::string>();
    auto* cmd = top->add_subcommand("pack", "zip a project for sharing (NAME.vxr.zip beside it)");
    cmd->add_option("name", *name, "project name or folder")->required();
    cmd->add_option("-o,--out", *out, "zip file to write (default NAME.vxr.zip)");
    cmd->callback([&inv, name, out] { inv.run = [name, out] { return run_pack(*name, *out); }; });
  }
}

}  // namespace vxr::cli
