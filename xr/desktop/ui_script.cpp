#include "xr/desktop/ui_script.h"

#include <filesystem>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/output_file.h"

namespace vxr::xr {
namespace {

std::vector<std::string> words(const std::string& line) {
  std::istringstream in(line);
  std::vector<std::string> w;
  for (std::string tok; in >> tok;) w.push_back(tok);
  return w;
}

bool parse_number(const std::string& s, double* out) {
  char* end = nullptr;
  *out = std::strtod(s.c_str(), &end);
  return !s.empty() && end == s.c_str() + s.size() && std::isfinite(*out);
}

// The step's shape; viewer commands are checked by applying them to a copy.
Result<UiStep> parse_step(const std::string& text) {
  UiStep step;
  step.text = text;
  const std::vector<std::string> w = words(text);
  if (w.empty()) return invalid_argument("empty step");
  const std::string& cmd = w[0];
  if (cmd == "ui") {
    if (w.size() != 2 || (w[1] != "on" && w[1] != "off")) return invalid_argument("usage: ui on|off");
    step.kind = UiStepKind::kUi;
    step.on = w[1] == "on";
  } else if (cmd == "wait") {
    double n = 0;
    if (w.size() != 2 || !parse_number(w[1], &n) || n < 1 || n > 100000 || n != std::floor(n))
      return invalid_argument("usage: wait FRAMES (1..100000)");
    step.kind = UiStepKind::kWait;
    step.frames = uint64_t(n);
  } else if (cmd == "resize") {
    if (w.size() != 3 || !parse_number(w[1], &step.xyz[0]) || !parse_number(w[2], &step.xyz[1]) ||
        step.xyz[0] < 64 || step.xyz[1] < 64 || step.xyz[0] > 8192 || step.xyz[1] > 8192 ||
        step.xyz[0] != std::floor(step.xyz[0]) || step.xyz[1] != std::floor(step.xyz[1]))
      return invalid_argument("usage: resize WIDTH HEIGHT (64..8192 pixels)");
    step.kind = UiStepKind::kResize;
  } else if (cmd == "tool") {
    const bool with_class = w.size() >= 2 && (w[1] == "count" || w[1] == "track");
    if (!((w.size() == 2 && (with_class || w[1] == "navigate" || w[1] == "measure" || w[1] == "trace" ||
                             w[1] == "roi")) ||
          (w.size() == 3 && with_class)))
      return invalid_argument("usage: tool navigate|count [CLASS]|measure|trace|track [CLASS]|roi");
    step.kind = UiStepKind::kTool;
    step.arg = w[1] + (w.size() == 3 ? " " + w[2] : with_class ? " default" : "");
  } else if (cmd == "drag") {
    bool ok = w.size() == 5;
    for (size_t i = 0; ok && i < 4; ++i) ok = parse_number(w[i + 1], &step.xyz[i]) && step.xyz[i] >= 0;
    if (!ok) return invalid_argument("usage: drag X Y X2 Y2 (window pixels)");
    step.kind = UiStepKind::kDrag;
  } else if (cmd == "finish") {
    if (w.size() != 1) return invalid_argument("usage: finish");
    step.kind = UiStepKind::kFinish;
  } else if (cmd == "remove") {
    if (w.size() != 3 || !annotation_kind_from_name(w[1]) || !parse_number(w[2], &step.xyz[0]) || step.xyz[0] < 1 ||
        step.xyz[0] != std::floor(step.xyz[0]))
      return invalid_argument("usage: remove marker|measurement|skeleton|track|roi ID");
    step.kind = UiStepKind::kRemove;
    step.arg = w[1];
  } else if (cmd == "keyframe") {
    if (w.size() != 1) return invalid_argument("usage: keyframe");
    step.kind = UiStepKind::kKeyframe;
  } else if (cmd == "export-movie") {
    double frames = 0;
    step.xyz[0] = 30.0;
    if ((w.size() != 3 && w.size() != 4) || !parse_number(w[2], &frames) || frames < 2 || frames > 100000 ||
        frames != std::floor(frames) || (w.size() == 4 && (!parse_number(w[3], &step.xyz[0]) || step.xyz[0] <= 0)))
      return invalid_argument("usage: export-movie OUT FRAMES [FPS] (FRAMES 2..100000; OUT a folder or NAME.mp4)");
    step.kind = UiStepKind::kExportMovie;
    step.arg = w[1];
    step.frames = uint64_t(frames);
  } else if (cmd == "panel-card") {
    if (w.size() < 2) return invalid_argument("usage: panel-card TITLE");
    step.kind = UiStepKind::kPanelCard;
    step.arg = text.substr(text.find("panel-card") + 10);
    step.arg.erase(0, step.arg.find_first_not_of(" \t"));
  } else if (cmd == "open") {
    if (w.size() != 2) return invalid_argument("usage: open PATH (no spaces)");
    step.kind = UiStepKind::kOpen;
    step.arg = w[1];
  } else if (cmd == "restore-card") {
    if (w.size() != 2 || !parse_number(w[1], &step.xyz[0]) || step.xyz[0] < 1 || step.xyz[0] != std::floor(step.xyz[0]))
      return invalid_argument("usage: restore-card ID");
    step.kind = UiStepKind::kRestoreCard;
  } else if (cmd == "click") {
    if (w.size() != 3 || !parse_number(w[1], &step.xyz[0]) || !parse_number(w[2], &step.xyz[1]) || step.xyz[0] < 0 ||
        step.xyz[1] < 0)
      return invalid_argument("usage: click X Y (window pixels)");
    step.kind = UiStepKind::kClick;
  } else if (cmd == "screenshot") {
    if (w.size() != 2) return invalid_argument("usage: screenshot PATH (no spaces)");
    step.kind = UiStepKind::kScreenshot;
    step.arg = w[1];
  } else if (cmd == "count" || cmd == "measure") {
    const size_t n = cmd == "count" ? 3 : 6;
    if (w.size() != n + 1 && !(cmd == "count" && w.size() == n + 2))
      return invalid_argument(cmd == "count" ? "usage: count X Y Z [CLASS]" : "usage: measure X Y Z X2 Y2 Z2");
    for (size_t i = 0; i < n; ++i)
      if (!parse_number(w[i + 1], &step.xyz[i])) return invalid_argument("'" + w[i + 1] + "' is not a number");
    step.kind = cmd == "count" ? UiStepKind::kCount : UiStepKind::kMeasure;
    step.arg = w.size() == n + 2 ? w[n + 1] : "default";
  } else if (cmd == "card") {
    if (w.size() < 2) return invalid_argument("usage: card TITLE");
    step.kind = UiStepKind::kCard;
    step.arg = text.substr(text.find("card") + 4);
    step.arg.erase(0, step.arg.find_first_not_of(" \t"));
  } else {
    step.kind = UiStepKind::kViewer;
  }
  return step;
}

}  // namespace

Status UiScript::step_error(size_t index, const std::string& why) const {
  const std::string text = index < steps.size() ? steps[index].text : std::string();
  // Viewer commands already quote themselves ("'LINE': WHY"): say it once.
  const std::string quoted = "'" + text + "': ";
  const std::string reason = why.rfind(quoted, 0) == 0 ? why.substr(quoted.size()) : why;
  return invalid_argument(path + ": step " + std::to_string(index + 1) + " ('" + text + "'): " + reason);
}

Result<UiScript> load_ui_script(const std::string& path, const ViewerState& state,
                                const std::vector<std::string>& inputs, bool have_store) {
  VXR_RETURN_IF_ERROR(check_input(path));
  std::ifstream in(path, std::ios::binary);
  if (!in) return not_found(path + ": cannot open the UI script");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  nlohmann::json j = nlohmann::json::parse(text, nullptr, false);
  if (j.is_discarded()) return invalid_argument(path + ": not JSON");
  if (j.is_object()) {
    if (!j.contains("steps")) return invalid_argument(path + ": expected a list of steps or {\"steps\": [...]}");
    j = j["steps"];
  }
  if (!j.is_array()) return invalid_argument(path + ": expected a list of steps or {\"steps\": [...]}");
  if (j.empty()) return invalid_argument(path + ": the script has no steps");
  UiScript script;
  script.path = path;
  ViewerState dry_run = state;
  std::vector<std::string> shots;
  size_t keyframes = 0;
  for (size_t i = 0; i < j.size(); ++i) {
    if (!j[i].is_string())
      return invalid_argument(path + ": step " + std::to_string(i + 1) + ": expected a string, got " +
                              std::string(j[i].type_name()));
    auto step = parse_step(j[i].get<std::string>());
    script.steps.push_back(step ? *step : UiStep{UiStepKind::kViewer, j[i].get<std::string>()});
    if (!step) return script.step_error(i, step.status().message());
    switch (step->kind) {
      case UiStepKind::kViewer:
        if (Status s = dry_run.apply_command(step->text); !s) return script.step_error(i, s.message());
        break;
      case UiStepKind::kScreenshot:
        if (Status s = check_output(step->arg, inputs, "screenshot"); !s) return script.step_error(i, s.message());
        for (const std::string& earlier : shots)
          if (earlier == step->arg) return script.step_error(i, "an earlier step already writes " + earlier);
        shots.push_back(step->arg);
        break;
      case UiStepKind::kCount:
      case UiStepKind::kMeasure:
      case UiStepKind::kCard:
      case UiStepKind::kTool:
      case UiStepKind::kClick:
      case UiStepKind::kDrag:
      case UiStepKind::kFinish:
      case UiStepKind::kRemove:
      case UiStepKind::kPanelCard:
      case UiStepKind::kRestoreCard:
        if (!have_store) return script.step_error(i, "needs an annotation store (--annotations STORE)");
        break;
      case UiStepKind::kKeyframe: ++keyframes; break;
      case UiStepKind::kOpen: {
        std::error_code ec;
        if (i + 1 != j.size()) return script.step_error(i, "open must be the last step (the window closes on it)");
        if (!std::filesystem::exists(step->arg, ec)) return script.step_error(i, step->arg + " does not exist");
        break;
      }
      case UiStepKind::kExportMovie: {
        if (keyframes < 2)
          return script.step_error(i, "needs 2 keyframe steps before it (" + std::to_string(keyframes) + " so far)");
        const Status s = check_movie_output({step->arg, step->frames, step->xyz[0]}, inputs);
        if (!s) return script.step_error(i, s.message());
        for (const std::string& earlier : shots)
          if (earlier == step->arg) return script.step_error(i, "an earlier step already writes " + earlier);
        shots.push_back(step->arg);
        break;
      }
      case UiStepKind::kUi:
      case UiStepKind::kWait:
      case UiStepKind::kResize: break;
    }
  }
  return script;
}

UiScriptRunner::UiScriptRunner(UiScript script, ViewerTools* tools,
                               std::function<Scene(const ViewerState&)> card_scene)
    : script_(std::move(script)), tools_(tools), card_scene_(std::move(card_scene)) {}

Result<UiScriptRunner::FrameWork> UiScriptRunner::before_frame(ViewerState& state) {
  FrameWork work;
  if (wait_ > 0) {
    --wait_;
    return work;
  }
  // State edits and tool events run back to back; a screenshot or a wait ends the frame's share.
  while (next_ < script_.steps.size()) {
    const size_t index = next_++;
    const UiStep& step = script_.steps[index];
    if (step.kind == UiStepKind::kScreenshot) {
      work.screenshot = step.arg;
      return work;
    }
    if (step.kind == UiStepKind::kWait) {
      wait_ = step.frames - 1;
      return work;
    }
    if (step.kind == UiStepKind::kResize) {
      work.resize = {int(step.xyz[0]), int(step.xyz[1])};
      return work;
    }
    if (step.kind == UiStepKind::kTool) {
      work.tool = step.arg;
      continue;
    }
    if (step.kind == UiStepKind::kRestoreCard) {
      work.restore_card = uint64_t(step.xyz[0]);
      continue;
    }
    if (step.kind == UiStepKind::kOpen) {
      work.open = step.arg;
      return work;
    }
    if (step.kind == UiStepKind::kPanelCard) {  // the picture is this frame's
      work.panel_card = step.arg;
      return work;
    }
    // One click or drag a frame, seen through that frame's camera.
    if (step.kind == UiStepKind::kClick) {
      work.click = std::array<double, 2>{step.xyz[0], step.xyz[1]};
      return work;
    }
    if (step.kind == UiStepKind::kDrag) {
      work.drag = std::array<double, 4>{step.xyz[0], step.xyz[1], step.xyz[2], step.xyz[3]};
      return work;
    }
    if (step.kind == UiStepKind::kFinish) {  // after a tool step of the same frame, before the next
      work.finish = true;
      return work;
    }
    if (step.kind == UiStepKind::kRemove) {
      work.remove = std::pair{*annotation_kind_from_name(step.arg), annotate::Id(step.xyz[0])};
      return work;
    }
    if (step.kind == UiStepKind::kKeyframe) {  // the camera of this frame, after the steps before it
      work.keyframe = true;
      return work;
    }
    if (step.kind == UiStepKind::kExportMovie) {
      work.export_movie = MovieRequest{step.arg, step.frames, step.xyz[0]};
      return work;
    }
    if (Status s = run_step(step, state); !s) return script_.step_error(index, s.message());
  }
  work.done = true;
  return work;
}

Status UiScriptRunner::run_step(const UiStep& step, ViewerState& state) {
  const bool needs_store = step.kind == UiStepKind::kCount || step.kind == UiStepKind::kMeasure ||
                           step.kind == UiStepKind::kCard;
  if (needs_store && !tools_) return internal_error("no annotation store");
  const uint32_t t = state.scene().timepoint;
  switch (step.kind) {
    case UiStepKind::kViewer: return state.apply_command(step.text);
    case UiStepKind::kUi:
      if (state.ui_visible() != step.on) state.handle_key(ViewerKey::kToggleUi);
      return Status::ok();
    case UiStepKind::kCount: return tools_->count({step.xyz[0], step.xyz[1], step.xyz[2]}, step.arg, t);
    case UiStepKind::kMeasure:
      return tools_->measure({step.xyz[0], step.xyz[1], step.xyz[2]}, {step.xyz[3], step.xyz[4], step.xyz[5]}, t);
    case UiStepKind::kCard: {
      std::vector<uint8_t> png;
      if (!last_screenshot_.empty()) {
        std::ifstream in(last_screenshot_, std::ios::binary);
        png.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
        if (!in.good() && !in.eof()) return io_error(last_screenshot_ + ": cannot read the screenshot back");
      }
      return tools_->card(card_scene_(state), step.arg, "", std::move(png)).status();
    }
    case UiStepKind::kScreenshot:
    case UiStepKind::kWait:
    case UiStepKind::kResize:
    case UiStepKind::kTool:
    case UiStepKind::kClick:
    case UiStepKind::kDrag:
    case UiStepKind::kFinish:
    case UiStepKind::kRemove:
    case UiStepKind::kKeyframe:
    case UiStepKind::kExportMovie:
    case UiStepKind::kPanelCard:
    case UiStepKind::kRestoreCard:
    case UiStepKind::kOpen: break;
  }
  return Status::ok();
}

}  // namespace vxr::xr
