// `vxr catalog PROJECT... -o DIR`: the paper's syBook browser as a static
// site. index.html holds every card as plain HTML (grouped by project in the
// grid view, by day in the timeline view); catalog.js only switches views and
// filters, so the page reads the same without scripts. No network: no fonts,
// scripts or images from elsewhere; thumbnails are the cards' snapshots copied
// into DIR/thumbs/.
#include <algorithm>
#include <cctype>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <map>
#include <span>

#include "annotate/annotation_store.h"
#include "annotate/file_io.h"
#include "annotate/project.h"
#include "command.h"
#include "core/output_file.h"

namespace vxr::cli {

using namespace vxr::annotate;
namespace fs = std::filesystem;

namespace {

std::string esc(const std::string& s) {
  std::string o;
  o.reserve(s.size());
  for (char c : s) {
    switch (c) {
      case '&': o += "&amp;"; break;
      case '<': o += "&lt;"; break;
      case '>': o += "&gt;"; break;
      case '"': o += "&quot;"; break;
      case '\'': o += "&#39;"; break;
      default: o += c;
    }
  }
  return o;
}

std::string utc(int64_t t, const char* format) {
  const std::time_t tt = static_cast<std::time_t>(t);
  std::tm tm{};
  gmtime_r(&tt, &tm);
  char buf[40];
  std::strftime(buf, sizeof buf, format, &tm);
  return buf;
}

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

struct Entry {
  size_t project;  // index into the projects
  Card card;
  std::string thumb;  // relative to DIR, "" when the card has no picture
};

struct Loaded {
  std::string folder;
  ProjectInfo info;
};

constexpr const char* kCss = R"(/* vxr catalogue: system fonts only, no network. */
:root { --bg: #f6f5f2; --fg: #1d1d1f; --muted: #6b6b70; --card: #fff; --accent: #2d6cdf; }
* { box-sizing: border-box; }
body { margin: 0; font: 15px/1.45 system-ui, sans-serif; background: var(--bg); color: var(--fg); }
header { padding: 16px 24px; background: #20242c; color: #fff; display: flex; gap: 16px; align-items: center; flex-wrap: wrap; }
header h1 { font-size: 20px; margin: 0 16px 0 0; }
header .count { color: #c9ccd3; }
nav button { font: inherit; padding: 6px 14px; border: 1px solid #596070; background: #2f3440; color: #fff; border-radius: 6px; cursor: pointer; }
nav button[aria-pressed="true"] { background: var(--accent); border-color: var(--accent); }
header input { font: inherit; padding: 6px 10px; border-radius: 6px; border: 1px solid #596070; min-width: 220px; }
main { padding: 8px 24px 32px; }
section.project { margin-top: 24px; }
section.project h2 { margin: 0 0 4px; font-size: 18px; }
.desc { margin: 0 0 6px; color: var(--muted); }
.tags { display: flex; gap: 6px; flex-wrap: wrap; margin: 4px 0; padding: 0; list-style: none; }
.tags li { background: #e3e8f4; color: #23407a; border-radius: 10px; padding: 1px 9px; font-size: 12px; }
.grid { display: grid; grid-template-columns: repeat(auto-fill, minmax(220px, 1fr)); gap: 16px; margin-top: 10px; }
article.card { background: var(--card); border-radius: 8px; box-shadow: 0 1px 3px rgba(0,0,0,.15); overflow: hidden; display: flex; flex-direction: column; }
article.card img, .nothumb { width: 100%; aspect-ratio: 1 / 1; object-fit: contain; background: #000; display: block; }
.nothumb { display: flex; align-items: center; justify-content: center; color: #999; font-size: 13px; }
article.card .body { padding: 10px 12px 12px; }
article.card h3 { font-size: 15px; margin: 0 0 2px; }
time { color: var(--muted); font-size: 12px; }
.note { white-space: pre-wrap; margin: 6px 0 0; font-size: 14px; }
#timeline ol { list-style: none; padding: 0; margin: 0; border-left: 3px solid #c6cbd6; }
#timeline h2 { font-size: 16px; margin: 24px 0 8px; }
#timeline li { display: flex; gap: 12px; margin: 0 0 12px 0; padding-left: 14px; position: relative; }
#timeline li::before { content: ""; position: absolute; left: -8px; top: 10px; width: 13px; height: 13px; border-radius: 50%; background: var(--accent); }
#timeline li img, #timeline li .nothumb { width: 96px; height: 96px; flex: none; border-radius: 6px; }
#timeline .proj { font-size: 12px; color: var(--accent); }
.hidden { display: none !important; }
)";

constexpr const char* kJs = R"(// vxr catalogue: view switch (grid / timeline, kept in the URL hash) and a
// text filter. Everything is already in the page; this only hides and shows.
(function () {
  "use strict";
  var views = ["grid", "timeline"];
  function show(view) {
    if (views.indexOf(view) < 0) view = "grid";
    views.forEach(function (v) {
      document.getElementById(v).classList.toggle("hidden", v !== view);
      document.getElementById("show-" + v).setAttribute("aria-pressed", v === view ? "true" : "false");
    });
  }
  function filter(text) {
    var words = text.toLowerCase().split(/\s+/).filter(function (w) { return w.length > 0; });
    document.querySelectorAll("[data-search]").forEach(function (el) {
      var hay = el.getAttribute("data-search");
      var hit = words.every(function (w) { return hay.indexOf(w) >= 0; });
      el.classList.toggle("hidden", !hit);
    });
  }
  function countBrokenImages() {
    var broken = 0;
    document.querySelectorAll("img").forEach(function (img) {
      if (!img.complete || img.naturalWidth === 0) broken += 1;
    });
    document.documentElement.setAttribute("data-broken-images", String(broken));
  }
  views.forEach(function (v) {
    document.getElementById("show-" + v).addEventListener("click", function () { location.hash = v; show(v); });
  });
  document.getElementById("filter").addEventListener("input", function (e) { filter(e.target.value); });
  window.addEventListener("hashchange", function () { show(location.hash.slice(1)); });
  show(location.hash.slice(1));
  window.addEventListener("load", countBrokenImages);
  document.documentElement.setAttribute("data-catalog-ready", "yes");
})();
)";

std::string thumb_html(const Entry& e, const std::string& title) {
  if (e.thumb.empty()) return "<div class=\"nothumb\">no snapshot</div>";
  return "<img src=\"" + esc(e.thumb) + "\" alt=\"" + esc(title) + "\" loading=\"eager\">";
}

std::string title_of(const Card& c) {
  if (!c.title.empty()) return c.title;
  const std::string first = c.note.substr(0, c.note.find('\n'));
  return first.empty() ? "Card " + std::to_string(c.id) : first.substr(0, 80);
}

std::string page(const std::vector<Loaded>& projects, const std::vector<Entry>& entries) {
  std::string h;
  h += "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
       "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
       "<title>vxr catalogue</title>\n<link rel=\"stylesheet\" href=\"catalog.css\">\n</head>\n<body>\n";
  h += "<header><h1>vxr catalogue</h1><span class=\"count\">" + std::to_string(entries.size()) + " card(s) in " +
       std::to_string(projects.size()) + " project(s)</span>\n"
       "<nav><button id=\"show-grid\" type=\"button\" aria-pressed=\"true\">Grid</button> "
       "<button id=\"show-timeline\" type=\"button\" aria-pressed=\"false\">Timeline</button></nav>\n"
       "<input id=\"filter\" type=\"search\" placeholder=\"Filter cards\" aria-label=\"Filter cards\"></header>\n<main>\n";
  auto search_text = [&](const Entry& e) {
    const Loaded& p = projects[e.project];
    std::string t = e.card.title + " " + e.card.note + " " + p.info.name;
    for (const std::string& tag : p.info.tags) t += " " + tag;
    return esc(lower(t));
  };
  // Grid: one section per project, cards in id order.
  h += "<div id=\"grid\">\n";
  for (size_t pi = 0; pi < projects.size(); ++pi) {
    const ProjectInfo& p = projects[pi].info;
    h += "<section class=\"project\"><h2>" + esc(p.name) + "</h2>\n";
    if (!p.description.empty()) h += "<p class=\"desc\">" + esc(p.description) + "</p>\n";
    if (!p.tags.empty()) {
      h += "<ul class=\"tags\">";
      for (const std::string& t : p.tags) h += "<li>" + esc(t) + "</li>";
      h += "</ul>\n";
    }
    h += "<div class=\"grid\">\n";
    size_t n = 0;
    for (const Entry& e : entries) {
      if (e.project != pi) continue;
      ++n;
      const std::string title = title_of(e.card);
      h += "<article class=\"card\" id=\"card-" + std::to_string(pi) + "-" + std::to_string(e.card.id) +
           "\" data-search=\"" + search_text(e) + "\">" + thumb_html(e, title) + "<div class=\"body\"><h3>" + esc(title) +
           "</h3><time datetime=\"" + utc(e.card.created_unix, "%Y-%m-%dT%H:%M:%SZ") + "\">" +
           utc(e.card.created_unix, "%Y-%m-%d %H:%M UTC") + "</time>";
      if (!e.card.note.empty()) h += "<p class=\"note\">" + esc(e.card.note) + "</p>";
      h += "</div></article>\n";
    }
    if (n == 0) h += "<p class=\"desc\">no cards yet</p>\n";
    h += "</div></section>\n";
  }
  h += "</div>\n";
  // Timeline: every card by creation time, one list per UTC day.
  std::vector<const Entry*> by_time;
  for (const Entry& e : entries) by_time.push_back(&e);
  std::stable_sort(by_time.begin(), by_time.end(),
                   [](const Entry* a, const Entry* b) { return a->card.created_unix < b->card.created_unix; });
  h += "<div id=\"timeline\" class=\"hidden\">\n";
  std::string day;
  for (const Entry* e : by_time) {
    const std::string d = utc(e->card.created_unix, "%Y-%m-%d");
    if (d != day) {
      if (!day.empty()) h += "</ol>\n";
      h += "<h2>" + d + "</h2>\n<ol>\n";
      day = d;
    }
    const std::string title = title_of(e->card);
    h += "<li data-search=\"" + search_text(*e) + "\">" + thumb_html(*e, title) + "<div><span class=\"proj\">" +
         esc(projects[e->project].info.name) + "</span><h3>" + esc(title) + "</h3><time>" +
         utc(e->card.created_unix, "%H:%M UTC") + "</time>";
    if (!e->card.note.empty()) h += "<p class=\"note\">" + esc(e->card.note) + "</p>";
    h += "</div></li>\n";
  }
  if (!day.empty()) h += "</ol>\n";
  if (by_time.empty()) h += "<p class=\"desc\">no cards yet</p>\n";
  h += "</div>\n</main>\n<script src=\"catalog.js\"></script>\n</body>\n</html>\n";
  return h;
}

int run_catalog(const std::vector<std::string>& names, const std::string& out) {
  std::vector<Loaded> projects;
  std::vector<Entry> entries;
  std::vector<std::string> inputs;  // every file the catalogue reads: none may be overwritten
  for (const std::string& n : names) {
    Loaded l;
    l.folder = project_folder(n);
    auto info = read_project(l.folder);
    if (!info) return fail(info.status(), info.status().code() == ErrorCode::kNotFound ? kExitUsage : kExitFailure);
    l.info = *info;
    if (l.info.name.empty()) l.info.name = fs::path(l.folder).stem().string();
    std::error_code ec;
    const fs::path o = fs::weakly_canonical(out, ec), root = fs::weakly_canonical(l.folder, ec);
    if (o == root || o.string().rfind(root.string() + "/", 0) == 0)
      return fail(invalid_argument("-o " + out + ": inside the project " + l.folder + "; write the catalogue elsewhere"),
                  kExitUsage);
    inputs.push_back((fs::path(l.folder) / "project.json").string());
    projects.push_back(std::move(l));
  }
  std::error_code ec;
  if (fs::exists(out, ec) && !fs::is_directory(out, ec))
    return fail(invalid_argument("-o " + out + ": exists and is not a folder"), kExitUsage);
  fs::create_directories(fs::path(out) / "thumbs", ec);
  if (ec) return fail(io_error(out + ": cannot create the folder (" + ec.message() + ")"));

  // Writes one output file, never over anything the catalogue read.
  auto put = [&](const std::string& rel, std::span<const uint8_t> bytes) -> Status {
    const std::string path = (fs::path(out) / rel).string();
    VXR_RETURN_IF_ERROR(check_output(path, inputs, "-o"));
    return write_file_atomically(path, bytes);
  };
  auto put_text = [&](const std::string& rel, const std::string& text) {
    return put(rel, std::span<const uint8_t>(reinterpret_cast<const uint8_t*>(text.data()), text.size()));
  };

  for (size_t pi = 0; pi < projects.size(); ++pi) {
    const std::string store_path = (fs::path(projects[pi].folder) / projects[pi].info.annotations).string();
    auto store = AnnotationStore::open(store_path, /*create=*/false);
    if (!store) return fail(store.status());
    auto cards = (*store)->cards();
    if (!cards) return fail(cards.status());
    for (const Card& summary : *cards) {
      auto card = (*store)->card(summary.id, /*with_media=*/true);
      if (!card) return fail(card.status());
      Entry e{pi, std::move(*card), ""};
      const std::string thumb = "thumbs/p" + std::to_string(pi) + "-card" + std::to_string(e.card.id) + ".png";
      std::vector<uint8_t> png = e.card.snapshot_png;
      if (png.empty() && !e.card.snapshot_path.empty()) {
        auto bytes = read_whole_file(e.card.snapshot_path);
        if (bytes) {
          png.assign(bytes->begin(), bytes->end());
          inputs.push_back(e.card.snapshot_path);
        } else {
          std::fprintf(stderr, "vxr: note: %s card %llu: %s; shown without a thumbnail\n", projects[pi].folder.c_str(),
                       (unsigned long long)e.card.id, bytes.status().message().c_str());
        }
      }
      if (!png.empty()) {
        if (Status st = put(thumb, png); !st) return fail(st);
        e.thumb = thumb;
      }
      // Audio memos are not in the catalogue: it shows pictures and notes.
      e.card.snapshot_png.clear();
      e.card.audio_wav.clear();
      entries.push_back(std::move(e));
    }
  }
  if (Status st = put_text("catalog.css", kCss); !st) return fail(st);
  if (Status st = put_text("catalog.js", kJs); !st) return fail(st);
  if (Status st = put_text("index.html", page(projects, entries)); !st) return fail(st);
  std::printf("%s: %zu card(s) from %zu project(s)\n", (fs::path(out) / "index.html").string().c_str(), entries.size(),
              projects.size());
  return kExitOk;
}

}  // namespace

void add_catalog_command(CLI::App& app, Invocation& inv) {
  auto names = std::make_shared<std::vector<std::string>>();
  auto out = std::make_shared<std::string>();
  auto* cmd = app.add_subcommand("catalog", "write a static HTML catalogue of the projects' cards (grid and timeline)");
  cmd->add_option("projects", *names, "project names or NAME.vxr folders")->required();
  cmd->add_option("-o,--out", *out, "folder to write index.html, catalog.css, catalog.js and thumbs/ into")->required();
  cmd->callback([&inv, names, out] { inv.run = [names, out] { return run_catalog(*names, *out); }; });
}

}  // namespace vxr::cli
