#include "annotate/swc.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <unordered_map>

#include "annotate/file_io.h"

namespace vxr::annotate {

const char* swc_warning_kind_name(SwcWarningKind kind) {
  switch (kind) {
    case SwcWarningKind::kMissingParent:
      return "missing-parent";
    case SwcWarningKind::kSeveralRoots:
      return "several-roots";
    case SwcWarningKind::kNonPositiveId:
      return "non-positive-id";
    case SwcWarningKind::kUndefinedType:
      return "undefined-type";
    case SwcWarningKind::kZeroRadiusSoma:
      return "zero-radius-soma";
    case SwcWarningKind::kNegativeRadius:
      return "negative-radius";
    case SwcWarningKind::kOddRootParent:
      return "odd-root-parent";
    case SwcWarningKind::kExtraColumns:
      return "extra-columns";
    case SwcWarningKind::kLongSegment:
      return "long-segment";
    case SwcWarningKind::kRadiusJump:
      return "radius-jump";
  }
  return "?";
}

bool SwcFile::has(SwcWarningKind kind) const {
  return std::any_of(warnings.begin(), warnings.end(), [&](const SwcWarning& w) { return w.kind == kind; });
}

std::vector<int> SwcFile::lines_with(SwcWarningKind kind) const {
  std::vector<int> out;
  for (const SwcWarning& w : warnings)
    if (w.kind == kind) out.push_back(w.line);
  return out;
}

namespace {

bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}

bool parse_double(std::string_view tok, double* out) {
  if (!tok.empty() && tok[0] == '+') tok.remove_prefix(1);
  const auto [end, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), *out);
  return ec == std::errc() && end == tok.data() + tok.size() && std::isfinite(*out);
}

// Ids, types and parents are integers, but some writers print them as "5.0".
bool parse_integer(std::string_view tok, int64_t* out) {
  double d = 0;
  if (!parse_double(tok, &d) || d != std::floor(d) || std::fabs(d) > 9.0e15) return false;
  *out = static_cast<int64_t>(d);
  return true;
}

// A token as it may be quoted in a message: binary input must not reach the terminal raw.
std::string printable(std::string_view tok) {
  std::string out;
  for (char c : tok.substr(0, 24)) out += (c >= 0x20 && c < 0x7f) ? c : '?';
  return tok.size() > 24 ? out + "..." : out;
}

std::string fmt_num(double v) {
  char buf[64];
  const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v);
  return ec == std::errc() ? std::string(buf, end) : std::string("nan");
}

}  // namespace

Result<SwcFile> parse_swc(const std::string& text, const std::string& name) {
  SwcFile file;
  auto where = [&](int line) { return name + ":" + std::to_string(line) + ": "; };
  auto warn = [&](int line, SwcWarningKind kind, const std::string& msg) {
    file.warnings.push_back({line, kind, where(line) + msg});
  };
  static const char* kColumns[7] = {"id", "type", "x", "y", "z", "radius", "parent"};

  int line_no = 0;
  size_t pos = 0;
  while (pos < text.size()) {
    size_t eol = text.find('\n', pos);
    if (eol == std::string::npos) eol = text.size();
    std::string_view line(text.data() + pos, eol - pos);
    pos = eol + 1;
    ++line_no;
    if (const size_t hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
    std::vector<std::string_view> tok;
    for (size_t i = 0; i < line.size();) {
      while (i < line.size() && is_space(line[i])) ++i;
      size_t j = i;
      while (j < line.size() && !is_space(line[j])) ++j;
      if (j > i) tok.push_back(line.substr(i, j - i));
      i = j;
    }
    if (tok.empty()) continue;
    if (tok.size() < 7) {
      return invalid_argument(where(line_no) + "expected 7 columns (id type x y z radius parent), found " +
                              std::to_string(tok.size()));
    }
    if (tok.size() > 7)
      warn(line_no, SwcWarningKind::kExtraColumns, std::to_string(tok.size()) + " columns; only the first 7 are read");
    SwcSample s;
    s.line = line_no;
    double v[7];
    for (int c = 0; c < 7; ++c) {
      if (!parse_double(tok[c], &v[c])) {
        return invalid_argument(where(line_no) + kColumns[c] + " '" + printable(tok[c]) + "' is not a number");
      }
    }
    int64_t type = 0;
    if (!parse_integer(tok[0], &s.id) || !parse_integer(tok[1], &type) || !parse_integer(tok[6], &s.parent) ||
        type < INT32_MIN || type > INT32_MAX) {
      return invalid_argument(where(line_no) + "id, type and parent must be whole numbers");
    }
    s.type = static_cast<int>(type);
    s.pos = {v[2], v[3], v[4]};
    s.radius = v[5];
    file.samples.push_back(s);
  }

  if (file.samples.empty())
    return invalid_argument(name + ": no samples (lines of id type x y z radius parent); is this an SWC file?");
  // Ids must be unique: a repeated id makes every reference to it ambiguous.
  std::unordered_map<int64_t, size_t> index;
  for (size_t i = 0; i < file.samples.size(); ++i) {
    const SwcSample& s = file.samples[i];
    auto [it, fresh] = index.emplace(s.id, i);
    if (!fresh) {
      return invalid_argument(where(s.line) + "sample id " + std::to_string(s.id) +
                              " is repeated (first defined on line " + std::to_string(file.samples[it->second].line) +
                              "); make ids unique");
    }
  }
  std::vector<int> root_lines;
  for (SwcSample& s : file.samples) {
    if (s.id <= 0)
      warn(s.line, SwcWarningKind::kNonPositiveId,
           "sample id " + std::to_string(s.id) + " is not positive (SWC ids start at 1); ids are shifted on import");
    if (s.type == 0)
      warn(s.line, SwcWarningKind::kUndefinedType,
           "sample " + std::to_string(s.id) + " has structure type 0 (undefined)");
    if (s.radius < 0)
      warn(s.line, SwcWarningKind::kNegativeRadius,
           "sample " + std::to_string(s.id) + " has a negative radius " + fmt_num(s.radius));
    if (s.type == 1 && s.radius == 0)
      warn(s.line, SwcWarningKind::kZeroRadiusSoma, "soma sample " + std::to_string(s.id) + " has radius 0");
    if (s.parent < 0) {
      if (s.parent != kNoParent) {
        warn(s.line, SwcWarningKind::kOddRootParent, "parent " + std::to_string(s.parent) + " read as -1 (a root)");
        s.parent = kNoParent;
      }
    } else if (s.parent == s.id) {
      return invalid_argument(where(s.line) + "sample " + std::to_string(s.id) + " is its own parent");
    } else if (!index.count(s.parent)) {
      warn(s.line, SwcWarningKind::kMissingParent,
           "sample " + std::to_string(s.id) + " names parent " + std::to_string(s.parent) +
               ", which is not in the file; it becomes a root");
      s.parent = kNoParent;
    }
    if (s.parent == kNoParent) root_lines.push_back(s.line);
  }
  if (root_lines.size() > 1) {
    std::string lines;
    for (size_t i = 0; i < root_lines.size() && i < 8; ++i) lines += (i ? ", " : "") + std::to_string(root_lines[i]);
    if (root_lines.size() > 8) lines += ", ...";
    warn(root_lines[1], SwcWarningKind::kSeveralRoots,
         std::to_string(root_lines.size()) + " roots (lines " + lines + "); each becomes its own tree");
  }
  // A parent chain that loops never reaches a root: refuse, naming a line on the loop.
  std::vector<char> state(file.samples.size(), 0);  // 0 unseen, 1 on the current walk, 2 reaches a root
  for (size_t i = 0; i < file.samples.size(); ++i) {
    std::vector<size_t> walk;
    size_t cur = i;
    while (state[cur] == 0) {
      state[cur] = 1;
      walk.push_back(cur);
      if (file.samples[cur].parent == kNoParent) break;
      cur = index.at(file.samples[cur].parent);
    }
    if (state[cur] == 1 && file.samples[cur].parent != kNoParent) {
      return invalid_argument(where(file.samples[cur].line) + "sample " + std::to_string(file.samples[cur].id) +
                              " is its own ancestor (the parent chain loops)");
    }
    for (size_t w : walk) state[w] = 2;
  }
  // Plausibility: outliers are kept but reported (often a typo in one column).
  std::vector<double> seg;
  for (const SwcSample& s : file.samples) {
    if (s.parent == kNoParent) continue;
    const SwcSample& p = file.samples[index.at(s.parent)];
    seg.push_back(std::hypot(s.pos[0] - p.pos[0], s.pos[1] - p.pos[1], s.pos[2] - p.pos[2]));
  }
  if (seg.size() >= 4) {
    std::vector<double> sorted = seg;
    std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
    const double median = sorted[sorted.size() / 2];
    size_t k = 0;
    for (const SwcSample& s : file.samples) {
      if (s.parent == kNoParent) continue;
      const double len = seg[k++];
      if (median > 0 && len > 10 * median) {
        warn(s.line, SwcWarningKind::kLongSegment,
             "sample " + std::to_string(s.id) + " is " + fmt_num(len) +
                 " from its parent, over 10x the median segment (" + fmt_num(median) + ")");
      }
    }
  }
  for (const SwcSample& s : file.samples) {
    if (s.parent == kNoParent) continue;
    const SwcSample& p = file.samples[index.at(s.parent)];
    if (p.type == 1 || s.type == 1) continue;  // soma radii are not neurite radii
    if (s.radius > 0 && p.radius > 0 && (s.radius > 10 * p.radius || p.radius > 10 * s.radius)) {
      warn(s.line, SwcWarningKind::kRadiusJump,
           "sample " + std::to_string(s.id) + " has radius " + fmt_num(s.radius) + ", its parent " + fmt_num(p.radius));
    }
  }
  std::stable_sort(file.warnings.begin(), file.warnings.end(),
                   [](const SwcWarning& a, const SwcWarning& b) { return a.line < b.line; });
  return file;
}

Result<SwcFile> read_swc(const std::string& path) {
  VXR_ASSIGN_OR_RETURN(std::string text, read_whole_file(path));
  return parse_swc(text, path);
}

Skeleton skeleton_from_swc(const SwcFile& file) {
  int64_t min_id = 1;
  for (const SwcSample& s : file.samples) min_id = std::min(min_id, s.id);
  const int64_t shift = 1 - min_id;  // 0 unless the file has ids <= 0
  Skeleton sk;
  for (const SwcSample& s : file.samples) {
    sk.insert_unchecked({s.id + shift, s.pos, s.radius, s.type, s.parent == kNoParent ? kNoParent : s.parent + shift});
  }
  return sk;
}

std::string skeleton_to_swc(const Skeleton& skeleton, const std::string& header,
                            std::map<int64_t, int64_t>* renumbered) {
  std::string out;
  size_t start = 0;
  while (start < header.size()) {
    size_t eol = header.find('\n', start);
    if (eol == std::string::npos) eol = header.size();
    out += "# " + header.substr(start, eol - start) + "\n";
    start = eol + 1;
  }
  out += "# id type x y z radius parent\n";
  std::map<int64_t, int64_t> num;
  int64_t next = 1;
  for (int64_t id : skeleton.parent_first_order()) num[id] = next++;
  for (int64_t id : skeleton.parent_first_order()) {
    const SkeletonNode& n = *skeleton.find(id);
    out += std::to_string(num.at(id)) + ' ' + std::to_string(n.type) + ' ' + fmt_num(n.pos[0]) + ' ' +
           fmt_num(n.pos[1]) + ' ' + fmt_num(n.pos[2]) + ' ' + fmt_num(n.radius) + ' ' +
           (n.parent == kNoParent ? std::string("-1") : std::to_string(num.at(n.parent))) + '\n';
  }
  if (renumbered) *renumbered = std::move(num);
  return out;
}

}  // namespace vxr::annotate
