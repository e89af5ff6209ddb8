// `vxr annotate ...` and `vxr cards ...`: the project's annotation store
// (engine/annotate) from the command line, for scripts and for people
// without a headset. Every subcommand takes the store folder first; results
// go to stdout one per line, problems to stderr as "vxr: ...".
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>

#include "annotate/annotation_store.h"
#include "core/output_file.h"
#include "annotate/csv_export.h"
#include "annotate/file_io.h"
#include "annotate/obj.h"
#include "annotate/swc.h"
#include "annotate/tool_script.h"
#include "command.h"
#include "scene/render_settings.h"

namespace vxr::cli {

using namespace vxr::annotate;
namespace fs = std::filesystem;

namespace {

// "x,y,z" (or n numbers) -> doubles; nullopt when malformed.
std::optional<std::vector<double>> parse_numbers(const std::string& s, size_t min_n, size_t max_n) {
  std::vector<double> out;
  size_t start = 0;
  while (start <= s.size()) {
    size_t comma = s.find(',', start);
    if (comma == std::string::npos) comma = s.size();
    double v = 0;
    const char* b = s.data() + start;
    const char* e = s.data() + comma;
    const auto [end, ec] = std::from_chars(b, e, v);
    if (ec != std::errc() || end != e || !std::isfinite(v)) return std::nullopt;
    out.push_back(v);
    start = comma + 1;
  }
  if (out.size() < min_n || out.size() > max_n) return std::nullopt;
  return out;
}

Result<Vec3> parse_point(const std::string& option, const std::string& s) {
  auto v = parse_numbers(s, 3, 3);
  if (!v) return invalid_argument(option + " '" + s + "': give three numbers x,y,z in voxels, e.g. 10,20.5,3");
  return Vec3{(*v)[0], (*v)[1], (*v)[2]};
}

Result<std::unique_ptr<AnnotationStore>> open_store(const std::string& path, bool create = false) {
  return AnnotationStore::open(path, create);
}

// Outputs must never replace what we read: the store folder (or anything in it).
Status check_store_output(const std::string& out, const std::string& store) {
  const std::string inputs[] = {store};
  return vxr::check_output(out, inputs, "-o");
}

std::string fmt(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}
std::string fmt3(const Vec3& v) {
  return fmt(v[0]) + "," + fmt(v[1]) + "," + fmt(v[2]);
}

std::string utc(int64_t t) {
  const std::time_t tt = static_cast<std::time_t>(t);
  std::tm tm{};
  gmtime_r(&tt, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%d %H:%M UTC", &tm);
  return buf;
}

int usage(const std::string& msg) {
  return fail(invalid_argument(msg), kExitUsage);
}

// Failures caused by what the user typed (bad id, bad value) are usage errors;
// the rest (I/O, damaged store) are failures.
int fail_status(const Status& s) {
  const bool usage_error = s.code() == ErrorCode::kInvalidArgument || s.code() == ErrorCode::kNotFound;
  return fail(s, usage_error ? kExitUsage : kExitFailure);
}

// Registers a subcommand whose body runs with the opened store.
template <typename Body>
CLI::App* store_command(CLI::App& parent, Invocation& inv, const char* name, const char* help,
                        std::shared_ptr<std::string> store, Body body, bool create = false) {
  CLI::App* cmd = parent.add_subcommand(name, help);
  cmd->add_option("store", *store, "annotation store folder (e.g. project.vxr/annotations)")->required();
  cmd->callback([&inv, store, body, create] {
    inv.run = [store, body, create] {
      auto s = open_store(*store, create);
      if (!s.is_ok()) return fail_status(s.status());
      return body(**s);
    };
  });
  return cmd;
}

void print_card_line(const Card& c) {
  std::printf("%llu\t%s\t%s%s%s\n", (unsigned long long)c.id, utc(c.created_unix).c_str(),
              c.title.empty() ? c.note.substr(0, c.note.find('\n')).substr(0, 60).c_str() : c.title.c_str(),
              c.snapshot_png.empty() && c.snapshot_path.empty() ? "" : "  [snapshot]",
              c.audio_wav.empty() ? "" : "  [memo]");
}

}  // namespace

void add_annotate_command(CLI::App& app, Invocation& inv) {
  auto* top =
      app.add_subcommand("annotate", "markers, measurements, skeletons (SWC), tracks and ROIs in a project's store");
  top->require_subcommand(1);

  {
    auto store = std::make_shared<std::string>();
    auto voxel = std::make_shared<std::string>();
    auto unit = std::make_shared<std::string>();
    auto* cmd = store_command(
        *top, inv, "init", "create the store (or open it) and set the voxel size used for lengths", store,
        [voxel, unit](AnnotationStore& s) {
          VoxelSpace vs = s.voxel_space();
          if (!voxel->empty()) {
            auto v = parse_numbers(*voxel, 3, 3);
            if (!v) return usage("--voxel-size '" + *voxel + "': give three positive numbers, e.g. 0.5,0.5,2");
            vs.voxel_size = {(*v)[0], (*v)[1], (*v)[2]};
          }
          if (!unit->empty()) vs.unit = *unit;
          if (!(vs == s.voxel_space())) {
            if (Status st = s.set_voxel_space(vs); !st.is_ok()) return fail(st, kExitUsage);
          }
          std::printf("%s: annotation store, schema %d, voxel size %s %s\n", s.path().c_str(),
                      AnnotationStore::kSchemaVersion, fmt3(vs.voxel_size).c_str(), vs.unit.c_str());
          return kExitOk;
        },
        /*create=*/true);
    cmd->add_option("--voxel-size", *voxel, "voxel size x,y,z (default 1,1,1)");
    cmd->add_option("--unit", *unit, "length unit: um, nm or mm (default um)");
  }
  {
    auto store = std::make_shared<std::string>();
    auto script = std::make_shared<std::string>();
    auto pick = std::make_shared<double>(5.0);
    auto* cmd = store_command(
        *top, inv, "play", "drive the analysis tools (count, measure, trace, track, roi) from a JSON event script",
        store, [script, pick](AnnotationStore& s) {
          auto text = read_whole_file(*script);
          if (!text.is_ok()) return fail_status(text.status());
          auto steps = parse_tool_script(*text, *script);
          if (!steps.is_ok()) return fail(steps.status(), kExitUsage);
          ToolPalette palette(s, *pick);
          std::string last;
          const Status st = run_tool_script(palette, *steps, [&last](const ToolStep& step, const ToolLiveState& live) {
            if (live.last_edit != last) std::printf("event %zu: %s\n", step.index, live.last_edit.c_str());
            last = live.last_edit;
          });
          if (!st) return fail_status(Status(st.code(), *script + ": " + st.message()));
          std::string counts;
          for (const auto& [cls, n] : palette.live().counts)
            counts += (counts.empty() ? "" : ", ") + cls + " " + std::to_string(n);
          std::printf("counts at the last timepoint: %s\n", counts.empty() ? "none" : counts.c_str());
          return kExitOk;
        });
    cmd->add_option("script", *script, "tool event script (JSON; see engine/annotate/tool_script.h)")->required();
    cmd->add_option("--pick-radius", *pick, "how near (voxels) pick/remove must be to an item (default 5)")
        ->check(CLI::Range(0.0, 1e6));
  }
  {
    auto store = std::make_shared<std::string>();
    store_command(*top, inv, "list", "what the store holds, one line per item", store, [](AnnotationStore& s) {
      auto markers = s.markers();
      auto measures = s.measurements();
      auto sks = s.skeletons();
      auto tracks = s.tracks();
      auto rois = s.rois();
      auto cards = s.cards();
      auto meshes = s.meshes();
      for (const Status* st : {&markers.status(), &measures.status(), &sks.status(), &tracks.status(), &rois.status(),
                               &cards.status(), &meshes.status()})
        if (!st->is_ok()) return fail(*st);
      const VoxelSpace& vs = s.voxel_space();
      std::printf("voxel size %s %s\n", fmt3(vs.voxel_size).c_str(), vs.unit.c_str());
      std::printf("%zu markers, %zu measurements, %zu skeletons, %zu tracks, %zu ROIs, %zu cards, %zu meshes\n",
                  markers->size(), measures->size(), sks->size(), tracks->size(), rois->size(), cards->size(),
                  meshes->size());
      for (const StoredMesh& m : *meshes)
        std::printf("mesh %llu %s: %llu triangles%s\n", (unsigned long long)m.id, m.name.c_str(),
                    (unsigned long long)m.triangles,
                    m.parent ? (", below mesh " + std::to_string(m.parent)).c_str() : "");
      for (const Measurement& m : *measures)
        std::printf("measurement %llu %s: %s %s\n", (unsigned long long)m.id, m.label.c_str(), fmt(s.length(m)).c_str(),
                    vs.unit.c_str());
      for (const SkeletonInfo& k : *sks) {
        auto sk = s.skeleton(k.id);
        if (!sk.is_ok()) return fail(sk.status());
        std::printf("skeleton %llu %s: %zu nodes, %zu roots\n", (unsigned long long)k.id, k.name.c_str(), sk->size(),
                    sk->roots().size());
      }
      for (const Track& t : *tracks)
        std::printf("track %llu %s: %zu markers\n", (unsigned long long)t.id, t.name.c_str(), t.markers.size());
      for (const Roi& r : *rois)
        std::printf("roi %llu %s: %s .. %s\n", (unsigned long long)r.id, r.name.c_str(), fmt3(r.min).c_str(),
                    fmt3(r.max).c_str());
      return kExitOk;
    });
  }
  {
    auto store = std::make_shared<std::string>();
    auto pos = std::make_shared<std::string>();
    auto cls = std::make_shared<std::string>("default");
    auto color = std::make_shared<std::string>();
    auto t = std::make_shared<uint32_t>(0);
    auto* cmd = store_command(*top, inv, "add-marker", "place a counting marker; prints its id", store,
                              [pos, cls, color, t](AnnotationStore& s) {
                                auto p = parse_point("--pos", *pos);
                                if (!p.is_ok()) return fail(p.status(), kExitUsage);
                                Marker m;
                                m.pos = *p;
                                m.cls = *cls;
                                m.timepoint = *t;
                                if (!color->empty()) {
                                  auto c = parse_numbers(*color, 3, 4);
                                  if (!c || std::any_of(c->begin(), c->end(), [](double v) { return v < 0 || v > 1; }))
                                    return usage("--color '" + *color + "': give r,g,b or r,g,b,a in 0..1");
                                  for (size_t i = 0; i < c->size(); ++i) m.color[i] = (*c)[i];
                                }
                                auto id = s.add_marker(m);
                                if (!id.is_ok()) return fail_status(id.status());
                                std::printf("marker %llu\n", (unsigned long long)*id);
                                return kExitOk;
                              });
    cmd->add_option("--pos", *pos, "position x,y,z in voxels")->required();
    cmd->add_option("--class", *cls, "counting class (default 'default')");
    cmd->add_option("--color", *color, "r,g,b[,a] in 0..1");
    cmd->add_option("--t", *t, "timepoint (default 0)");
  }
  {
    auto store = std::make_shared<std::string>();
    auto t = std::make_shared<int64_t>(-1);
    auto* cmd = store_command(*top, inv, "count", "markers per class (tab separated), then the total", store,
                              [t](AnnotationStore& s) {
                                auto c = *t >= 0 ? s.counts(static_cast<uint32_t>(*t)) : s.counts();
                                if (!c.is_ok()) return fail(c.status());
                                size_t total = 0;
                                for (const auto& [cls, n] : *c) {
                                  std::printf("%s\t%zu\n", cls.c_str(), n);
                                  total += n;
                                }
                                std::printf("total\t%zu\n", total);
                                return kExitOk;
                              });
    cmd->add_option("--t", *t, "count only this timepoint");
  }
  {
    auto store = std::make_shared<std::string>();
    auto from = std::make_shared<std::string>();
    auto to = std::make_shared<std::string>();
    auto label = std::make_shared<std::string>();
    auto t = std::make_shared<uint32_t>(0);
    auto* cmd = store_command(*top, inv, "measure", "store a two-point measurement; prints its metric length", store,
                              [from, to, label, t](AnnotationStore& s) {
                                auto a = parse_point("--from", *from);
                                auto b = parse_point("--to", *to);
                                if (!a.is_ok()) return fail(a.status(), kExitUsage);
                                if (!b.is_ok()) return fail(b.status(), kExitUsage);
                                Measurement m{0, *label, *a, *b, *t};
                                auto id = s.add_measurement(m);
                                if (!id.is_ok()) return fail_status(id.status());
                                std::printf("measurement %llu: %s %s\n", (unsigned long long)*id,
                                            fmt(s.length(m)).c_str(), s.voxel_space().unit.c_str());
                                return kExitOk;
                              });
    cmd->add_option("--from", *from, "first point x,y,z in voxels")->required();
    cmd->add_option("--to", *to, "second point x,y,z in voxels")->required();
    cmd->add_option("--label", *label, "a name for it");
    cmd->add_option("--t", *t, "timepoint (default 0)");
  }
  {
    auto store = std::make_shared<std::string>();
    auto markers = std::make_shared<std::string>();
    auto name = std::make_shared<std::string>();
    auto* cmd = store_command(*top, inv, "add-track", "link markers (one per timepoint) into a track; prints its id",
                              store, [markers, name](AnnotationStore& s) {
                                auto v = parse_numbers(*markers, 1, 100000);
                                if (!v) return usage("--markers '" + *markers + "': give marker ids, e.g. 3,7,12");
                                std::vector<Id> ids;
                                for (double d : *v) {
                                  if (d < 1 || d != std::floor(d))
                                    return usage("--markers: '" + fmt(d) + "' is not a marker id");
                                  ids.push_back(static_cast<Id>(d));
                                }
                                auto id = s.add_track(*name, ids);
                                if (!id.is_ok()) return fail_status(id.status());
                                std::printf("track %llu\n", (unsigned long long)*id);
                                return kExitOk;
                              });
    cmd->add_option("--markers", *markers, "marker ids, comma separated")->required();
    cmd->add_option("--name", *name, "track name");
  }
  {
    auto store = std::make_shared<std::string>();
    auto mn = std::make_shared<std::string>();
    auto mx = std::make_shared<std::string>();
    auto name = std::make_shared<std::string>();
    auto* cmd = store_command(*top, inv, "add-roi", "store a box region of interest; prints its id", store,
                              [mn, mx, name](AnnotationStore& s) {
                                auto a = parse_point("--min", *mn);
                                auto b = parse_point("--max", *mx);
                                if (!a.is_ok()) return fail(a.status(), kExitUsage);
                                if (!b.is_ok()) return fail(b.status(), kExitUsage);
                                auto id = s.add_roi({0, *name, *a, *b});
                                if (!id.is_ok()) return fail_status(id.status());
                                std::printf("roi %llu\n", (unsigned long long)*id);
                                return kExitOk;
                              });
    cmd->add_option("--min", *mn, "lowest corner x,y,z in voxels")->required();
    cmd->add_option("--max", *mx, "highest corner x,y,z in voxels")->required();
    cmd->add_option("--name", *name, "ROI name");
  }
  {
    auto store = std::make_shared<std::string>();
    auto roi = std::make_shared<Id>(0);
    auto mn = std::make_shared<std::string>();
    auto mx = std::make_shared<std::string>();
    auto t = std::make_shared<int64_t>(-1);
    auto* cmd = store_command(*top, inv, "query", "the annotations inside an ROI (--roi ID) or a box (--min/--max)",
                              store, [roi, mn, mx, t](AnnotationStore& s) {
                                Roi box;
                                if (*roi) {
                                  auto r = s.roi(*roi);
                                  if (!r.is_ok()) return fail_status(r.status());
                                  box = *r;
                                } else {
                                  if (mn->empty() || mx->empty())
                                    return usage("query: give --roi ID, or --min and --max");
                                  auto a = parse_point("--min", *mn);
                                  auto b = parse_point("--max", *mx);
                                  if (!a.is_ok()) return fail(a.status(), kExitUsage);
                                  if (!b.is_ok()) return fail(b.status(), kExitUsage);
                                  box.min = *a;
                                  box.max = *b;
                                }
                                auto q = *t >= 0 ? s.query(box, static_cast<uint32_t>(*t)) : s.query(box);
                                if (!q.is_ok()) return fail(q.status());
                                for (const Marker& m : q->markers)
                                  std::printf("marker %llu %s %s t=%u\n", (unsigned long long)m.id, m.cls.c_str(),
                                              fmt3(m.pos).c_str(), m.timepoint);
                                for (const Measurement& m : q->measurements)
                                  std::printf("measurement %llu %s %s %s\n", (unsigned long long)m.id, m.label.c_str(),
                                              fmt(s.length(m)).c_str(), s.voxel_space().unit.c_str());
                                for (const auto& [sk, n] : q->nodes)
                                  std::printf("node %llu/%lld %s\n", (unsigned long long)sk, (long long)n.id,
                                              fmt3(n.pos).c_str());
                                for (const Track& tr : q->tracks)
                                  std::printf("track %llu %s\n", (unsigned long long)tr.id, tr.name.c_str());
                                return kExitOk;
                              });
    cmd->add_option("--roi", *roi, "a stored ROI's id");
    cmd->add_option("--min", *mn, "lowest corner x,y,z in voxels");
    cmd->add_option("--max", *mx, "highest corner x,y,z in voxels");
    cmd->add_option("--t", *t, "only markers and measurements at this timepoint");
  }
  {
    auto store = std::make_shared<std::string>();
    auto file = std::make_shared<std::string>();
    auto name = std::make_shared<std::string>();
    auto* cmd = store_command(
        *top, inv, "import-swc", "read an SWC file (micrometres) into a new skeleton; warnings go to stderr", store,
        [file, name](AnnotationStore& s) {
          auto swc = read_swc(*file);
          if (!swc.is_ok()) return fail(swc.status());
          for (const SwcWarning& w : swc->warnings) std::fprintf(stderr, "vxr: warning: %s\n", w.message.c_str());
          const VoxelSpace& vs = s.voxel_space();
          const double to_unit = 1.0 / micrometres_per_unit(vs.unit);  // SWC is in um
          Skeleton sk = skeleton_from_swc(*swc);
          sk.set_name(name->empty() ? fs::path(*file).filename().string() : *name);
          for (auto [id, n] : sk.nodes()) {
            n.pos = vs.from_physical({n.pos[0] * to_unit, n.pos[1] * to_unit, n.pos[2] * to_unit});
            n.radius *= to_unit;
            sk.insert_unchecked(n);
          }
          auto id = s.add_skeleton(sk);
          if (!id.is_ok()) return fail(id.status());
          std::printf("skeleton %llu: %zu nodes from %s (%zu warnings)\n", (unsigned long long)*id, sk.size(),
                      file->c_str(), swc->warnings.size());
          return kExitOk;
        });
    cmd->add_option("file", *file, "SWC file")->required();
    cmd->add_option("--name", *name, "skeleton name (default: the file name)");
  }
  {
    auto store = std::make_shared<std::string>();
    auto file = std::make_shared<std::string>();
    auto alpha = std::make_shared<double>(1.0);
    auto voxels = std::make_shared<bool>(false);
    auto* cmd = store_command(
        *top, inv, "import-obj",
        "read a Wavefront OBJ surface (in the store's length unit) as meshes, one per o/g part; warnings go to stderr",
        store, [file, alpha, voxels](AnnotationStore& s) {
          auto obj = read_obj(*file);
          if (!obj.is_ok()) return fail_status(obj.status());
          for (const std::string& w : obj->warnings) std::fprintf(stderr, "vxr: warning: %s\n", w.c_str());
          Mesh mesh = std::move(obj->mesh);
          if (!*voxels)
            for (Vec3& p : mesh.positions) p = s.voxel_space().from_physical(p);
          auto ids = s.add_meshes(mesh, *alpha);
          if (!ids.is_ok()) return fail_status(ids.status());
          for (size_t i = 0; i < ids->size(); ++i) {
            const MeshPart& part = mesh.parts[i];
            std::printf("mesh %llu '%s'%s: %u triangles\n", (unsigned long long)(*ids)[i], part.name.c_str(),
                        part.parent < 0 ? "" : (" below mesh " + std::to_string((*ids)[size_t(part.parent)])).c_str(),
                        part.triangle_count);
          }
          return kExitOk;
        });
    cmd->add_option("file", *file, "OBJ file")->required();
    cmd->add_option("--opacity", *alpha, "opacity of the surfaces, 0..1 (default 1)")->check(CLI::Range(0.0, 1.0));
    cmd->add_flag("--voxels", *voxels, "the OBJ is in voxel coordinates, not the store's length unit");
  }
  {
    // The tracing tool's edits, one per call, each atomic and tree-preserving.
    struct EditArgs {
      Id skeleton = 0;
      std::string add, to;
      int64_t move = 0, del = 0, reparent = 0, split = 0, parent = kNoParent;
      Id merge_from = 0;
      int64_t from_node = 0;
      double radius = 1.0;
      int type = 0;
    };
    auto store = std::make_shared<std::string>();
    auto a = std::make_shared<EditArgs>();
    auto* cmd = store_command(
        *top, inv, "edit-skeleton",
        "one tracing edit: --add, --move, --delete, --reparent, --split or --merge-from (the tree stays valid)", store,
        [a](AnnotationStore& s) {
          const int actions =
              !a->add.empty() + (a->move > 0) + (a->del > 0) + (a->reparent > 0) + (a->split > 0) + (a->merge_from > 0);
          if (actions != 1)
            return usage(
                "edit-skeleton: give exactly one of --add, --move, --delete, --reparent, --split, --merge-from");
          Status st;
          if (!a->add.empty()) {
            auto p = parse_point("--add", a->add);
            if (!p.is_ok()) return fail(p.status(), kExitUsage);
            auto id = s.add_node(a->skeleton, {0, *p, a->radius, a->type, a->parent});
            if (!id.is_ok()) return fail_status(id.status());
            std::printf("node %lld\n", (long long)*id);
            return kExitOk;
          }
          if (a->move > 0) {
            auto p = parse_point("--to", a->to);
            if (!p.is_ok()) return fail(p.status(), kExitUsage);
            st = s.move_node(a->skeleton, a->move, *p);
          } else if (a->del > 0) {
            st = s.delete_node(a->skeleton, a->del);
          } else if (a->reparent > 0) {
            st = s.reparent_node(a->skeleton, a->reparent, a->parent);
          } else if (a->split > 0) {
            auto id = s.split_skeleton(a->skeleton, a->split);
            if (!id.is_ok()) return fail_status(id.status());
            std::printf("skeleton %llu\n", (unsigned long long)*id);
            return kExitOk;
          } else {
            if (a->from_node <= 0) return usage("--merge-from: give --from-node, the node of that skeleton to attach");
            auto map = s.merge_skeletons(a->skeleton, a->parent, a->merge_from, a->from_node);
            if (!map.is_ok()) return fail_status(map.status());
            std::printf("merged %zu nodes into skeleton %llu; node %lld is now %lld\n", map->size(),
                        (unsigned long long)a->skeleton, (long long)a->from_node, (long long)map->at(a->from_node));
            return kExitOk;
          }
          if (!st.is_ok()) return fail_status(st);
          std::printf("ok\n");
          return kExitOk;
        });
    cmd->add_option("--skeleton", a->skeleton, "skeleton id")->required();
    cmd->add_option("--add", a->add, "add a node at x,y,z (voxels) under --parent; prints its id");
    cmd->add_option("--move", a->move, "move node N to --to x,y,z");
    cmd->add_option("--to", a->to, "new position for --move");
    cmd->add_option("--delete", a->del, "delete node N; its children join its parent");
    cmd->add_option("--reparent", a->reparent, "attach node N (and its subtree) under --parent");
    cmd->add_option("--split", a->split, "move the subtree at node N into a new skeleton; prints its id");
    cmd->add_option("--merge-from", a->merge_from, "move skeleton S into this one, --from-node hung under --parent");
    cmd->add_option("--from-node", a->from_node, "with --merge-from: the node that becomes the attached root");
    cmd->add_option("--parent", a->parent, "parent node id, -1 for a root (default -1)");
    cmd->add_option("--radius", a->radius, "with --add: radius in the store's unit (default 1)");
    cmd->add_option("--type", a->type, "with --add: SWC type (default 0)");
  }
  {
    auto store = std::make_shared<std::string>();
    auto skel = std::make_shared<Id>(0);
    auto out = std::make_shared<std::string>();
    auto* cmd = store_command(*top, inv, "export-swc", "write a skeleton as SWC (micrometres), numbered parents first",
                              store, [store, skel, out](AnnotationStore& s) {
                                if (Status st = check_store_output(*out, *store); !st.is_ok()) return fail(st, kExitUsage);
                                auto sk = s.skeleton(*skel);
                                if (!sk.is_ok()) return fail_status(sk.status());
                                const VoxelSpace& vs = s.voxel_space();
                                const double to_um = micrometres_per_unit(vs.unit);
                                Skeleton um = *sk;
                                for (auto [id, n] : sk->nodes()) {
                                  const Vec3 p = vs.to_physical(n.pos);
                                  n.pos = {p[0] * to_um, p[1] * to_um, p[2] * to_um};
                                  n.radius *= to_um;
                                  um.insert_unchecked(n);
                                }
                                const std::string text = skeleton_to_swc(
                                    um, "skeleton " + std::to_string(*skel) + " '" + sk->name() + "' from " + s.path() +
                                            " (vxr " VXR_VERSION "), micrometres");
                                if (Status st = vxr::write_file_atomically(*out, text); !st.is_ok()) return fail(st);
                                std::printf("%s: %zu samples\n", out->c_str(), um.size());
                                return kExitOk;
                              });
    cmd->add_option("--skeleton", *skel, "skeleton id (see `vxr annotate list`)")->required();
    cmd->add_option("-o,--out", *out, "SWC file to write")->required();
  }
  {
    auto store = std::make_shared<std::string>();
    auto what = std::make_shared<std::string>();
    auto out = std::make_shared<std::string>();
    auto t = std::make_shared<int64_t>(-1);
    auto* cmd =
        store_command(*top, inv, "export-csv", "points, counts, measurements or tracks as CSV (stdout without -o)",
                      store, [store, what, out, t](AnnotationStore& s) {
                        if (!out->empty()) {
                          if (Status st = check_store_output(*out, *store); !st.is_ok()) return fail(st, kExitUsage);
                        }
                        auto markers = s.markers();
                        if (!markers.is_ok()) return fail(markers.status());
                        std::string csv;
                        if (*what == "points") {
                          csv = markers_csv(*markers, s.voxel_space());
                        } else if (*what == "counts") {
                          csv = counts_csv(*markers, *t);
                        } else if (*what == "measurements") {
                          auto ms = s.measurements();
                          if (!ms.is_ok()) return fail(ms.status());
                          csv = measurements_csv(*ms, s.voxel_space());
                        } else {
                          auto tr = s.tracks();
                          if (!tr.is_ok()) return fail(tr.status());
                          csv = tracks_csv(*tr, *markers, s.voxel_space());
                        }
                        if (out->empty()) {
                          std::fwrite(csv.data(), 1, csv.size(), stdout);
                          return kExitOk;
                        }
                        if (Status st = vxr::write_file_atomically(*out, csv); !st.is_ok()) return fail(st);
                        std::printf("%s: %s\n", out->c_str(), what->c_str());
                        return kExitOk;
                      });
    cmd->add_option("--what", *what, "points | counts | measurements | tracks")
        ->required()
        ->check(CLI::IsMember({"points", "counts", "measurements", "tracks"}));
    cmd->add_option("-o,--out", *out, "CSV file to write (default: stdout)");
    cmd->add_option("--t", *t, "counts: only this timepoint");
  }
}

void add_cards_command(CLI::App& app, Invocation& inv) {
  auto* top = app.add_subcommand("cards", "saved findings (scene, note, snapshot, memo) in a project's store");
  top->require_subcommand(1);
  {
    auto store = std::make_shared<std::string>();
    auto title = std::make_shared<std::string>();
    auto note = std::make_shared<std::string>();
    auto scene = std::make_shared<std::string>();
    auto snapshot = std::make_shared<std::string>();
    auto audio = std::make_shared<std::string>();
    auto snapshot_path = std::make_shared<std::string>();
    auto* cmd = store_command(*top, inv, "add", "store a card; prints its id", store,
                              [title, note, scene, snapshot, audio, snapshot_path](AnnotationStore& s) {
                                Card c;
                                c.title = *title;
                                c.note = *note;
                                if (!snapshot_path->empty()) {
                                  if (!snapshot->empty()) return usage("give --snapshot or --snapshot-path, not both");
                                  std::error_code ec;
                                  if (!fs::is_regular_file(*snapshot_path, ec))
                                    return usage("--snapshot-path " + *snapshot_path + ": no such file");
                                  c.snapshot_path = fs::absolute(*snapshot_path, ec).string();
                                }
                                if (!scene->empty()) {
                                  auto text = read_whole_file(*scene);
                                  if (!text.is_ok()) return fail(text.status(), kExitUsage);
                                  auto sc = scene_from_json(*text);
                                  if (!sc.is_ok()) return usage("--scene " + *scene + ": " + sc.status().message());
                                  c.scene_json = *text;
                                }
                                auto load = [](const std::string& path, std::vector<uint8_t>* out) -> Status {
                                  if (path.empty()) return Status::ok();
                                  VXR_ASSIGN_OR_RETURN(std::string bytes, read_whole_file(path));
                                  out->assign(bytes.begin(), bytes.end());
                                  return Status::ok();
                                };
                                if (Status st = load(*snapshot, &c.snapshot_png); !st.is_ok())
                                  return fail(st, kExitUsage);
                                if (Status st = load(*audio, &c.audio_wav); !st.is_ok()) return fail(st, kExitUsage);
                                auto id = s.add_card(c);
                                if (!id.is_ok()) return fail_status(id.status());
                                std::printf("card %llu\n", (unsigned long long)*id);
                                return kExitOk;
                              });
    cmd->add_option("--title", *title, "short title");
    cmd->add_option("--note", *note, "text note (searchable)");
    cmd->add_option("--scene", *scene, "Scene JSON to restore (render settings, camera)");
    cmd->add_option("--snapshot", *snapshot, "PNG picture kept in the store");
    cmd->add_option("--snapshot-path", *snapshot_path,
                    "PNG picture left where it is; the card records its absolute path");
    cmd->add_option("--audio", *audio, "WAV voice memo kept in the store");
  }
  {
    auto store = std::make_shared<std::string>();
    store_command(*top, inv, "list", "one card per line: id, created (UTC), title", store, [](AnnotationStore& s) {
      auto cards = s.cards();
      if (!cards.is_ok()) return fail(cards.status());
      for (const Card& c : *cards) {
        auto full = s.card(c.id);  // media sizes for the [snapshot]/[memo] flags
        if (!full.is_ok()) return fail(full.status());
        print_card_line(*full);
      }
      return kExitOk;
    });
  }
  {
    auto store = std::make_shared<std::string>();
    auto words = std::make_shared<std::vector<std::string>>();
    auto* cmd =
        store_command(*top, inv, "search", "cards whose title or note holds every word; exit 1 when none does", store,
                      [words](AnnotationStore& s) {
                        std::string q;
                        for (const std::string& w : *words) q += w + " ";
                        auto hits = s.search_cards(q);
                        if (!hits.is_ok()) return fail(hits.status());
                        for (const Card& c : *hits) print_card_line(c);
                        if (hits->empty()) {
                          std::fprintf(stderr, "vxr: no card matches '%s'\n", q.substr(0, q.size() - 1).c_str());
                          return kExitFailure;
                        }
                        return kExitOk;
                      });
    cmd->add_option("words", *words, "words to find (case-insensitive)")->required();
  }
  {
    auto store = std::make_shared<std::string>();
    auto id = std::make_shared<Id>(0);
    auto* cmd = store_command(*top, inv, "show", "a card's fields and its scene JSON", store, [id](AnnotationStore& s) {
      auto c = s.card(*id);
      if (!c.is_ok()) return fail_status(c.status());
      std::printf("card %llu\ncreated: %s\ntitle: %s\nsnapshot: %s\nmemo: %s\nnote:\n%s\nscene:\n%s\n",
                  (unsigned long long)c->id, utc(c->created_unix).c_str(), c->title.c_str(),
                  c->snapshot_png.empty() ? (c->snapshot_path.empty() ? "none" : c->snapshot_path.c_str())
                                          : (std::to_string(c->snapshot_png.size()) + " bytes PNG").c_str(),
                  c->audio_wav.empty() ? "none" : (std::to_string(c->audio_wav.size()) + " bytes WAV").c_str(),
                  c->note.c_str(), c->scene_json.empty() ? "(none)" : c->scene_json.c_str());
      return kExitOk;
    });
    cmd->add_option("id", *id, "card id")->required();
  }
  {
    auto store = std::make_shared<std::string>();
    auto id = std::make_shared<Id>(0);
    auto out = std::make_shared<std::string>();
    auto* cmd = store_command(
        *top, inv, "export", "write card-ID.json (+ .png, .wav) into a folder", store,
        [store, id, out](AnnotationStore& s) {
          if (Status st = check_store_output(*out, *store); !st.is_ok()) return fail(st, kExitUsage);
          auto c = s.card(*id);
          if (!c.is_ok()) return fail_status(c.status());
          std::error_code ec;
          fs::create_directories(*out, ec);
          if (ec) return fail(io_error(*out + ": cannot create the folder (" + ec.message() + ")"));
          const std::string base = (fs::path(*out) / ("card-" + std::to_string(*id))).string();
          nlohmann::json j = {{"id", c->id},
                              {"title", c->title},
                              {"note", c->note},
                              {"created_unix", c->created_unix},
                              {"created", utc(c->created_unix)}};
          j["scene"] =
              c->scene_json.empty() ? nlohmann::json(nullptr) : nlohmann::json::parse(c->scene_json, nullptr, false);
          if (!c->snapshot_png.empty())
            j["snapshot"] = base + ".png";
          else if (!c->snapshot_path.empty())
            j["snapshot"] = c->snapshot_path;
          if (!c->audio_wav.empty()) j["memo"] = base + ".wav";
          std::vector<std::string> written;
          auto put = [&](const std::string& path, const std::string& bytes) {
            Status st = vxr::write_file_atomically(path, bytes);
            if (st.is_ok()) written.push_back(path);
            return st;
          };
          if (!c->snapshot_png.empty()) {
            if (Status st = put(base + ".png", std::string(c->snapshot_png.begin(), c->snapshot_png.end()));
                !st.is_ok())
              return fail(st);
          }
          if (!c->audio_wav.empty()) {
            if (Status st = put(base + ".wav", std::string(c->audio_wav.begin(), c->audio_wav.end())); !st.is_ok())
              return fail(st);
          }
          if (Status st = put(base + ".json", j.dump(2) + "\n"); !st.is_ok()) return fail(st);
          for (const std::string& w : written) std::printf("%s\n", w.c_str());
          return kExitOk;
        });
    cmd->add_option("id", *id, "card id")->required();
    cmd->add_option("-o,--out", *out, "folder to write into")->required();
  }
}

}  // namespace vxr::cli
