// SWC neuron morphology files (INCF swc-specification, NeuroMorpho):
// `n T x y z R parent` per line, micrometres, `#` comments. The reader is
// tolerant of what real files contain (../shared/design/formats.md) and
// reports every problem with its line number: problems it can repair are
// warnings (the file still loads), the rest are one error naming the line.
// The writer renumbers samples so every parent comes before its children.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "annotate/skeleton.h"
#include "core/status.h"

namespace vxr::annotate {

struct SwcSample {
  int64_t id = 0;
  int type = 0;
  Vec3 pos{0, 0, 0};
  double radius = 0.0;
  int64_t parent = kNoParent;
  int line = 0;  // 1-based line in the file it came from
};

enum class SwcWarningKind {
  kMissingParent,   // parent id not in the file: the sample becomes a root
  kSeveralRoots,    // more than one tree (reported once, on the second root)
  kNonPositiveId,   // id 0 or negative: ids are shifted on import
  kUndefinedType,   // structure type 0
  kZeroRadiusSoma,  // a soma sample (type 1) with radius 0
  kNegativeRadius,  // radius < 0
  kOddRootParent,   // a negative parent other than -1, read as a root
  kExtraColumns,    // more than 7 columns: the extra ones are ignored
  kLongSegment,     // a segment more than 10x the file's median segment length
  kRadiusJump,      // a radius more than 10x its parent's (or a tenth of it)
};
const char* swc_warning_kind_name(SwcWarningKind kind);  // "missing-parent", ...

struct SwcWarning {
  int line = 0;
  SwcWarningKind kind{};
  std::string message;  // "<file>:<line>: ..." ready to print
};

struct SwcFile {
  std::vector<SwcSample> samples;  // in file order; missing/odd parents already turned into roots
  std::vector<SwcWarning> warnings;
  bool has(SwcWarningKind kind) const;
  std::vector<int> lines_with(SwcWarningKind kind) const;
};

// `name` is used in messages (usually the path). Errors (kInvalidArgument):
// a line that is not 7 numbers, a non-integer id/type/parent, a repeated id,
// a sample that is its own ancestor; each says "<name>:<line>: ...". A file
// with no samples at all is an error too ("<name>: no samples ...").
Result<SwcFile> parse_swc(const std::string& text, const std::string& name);
Result<SwcFile> read_swc(const std::string& path);

// The samples as a Skeleton (positions and radii still in micrometres).
// Ids <= 0 are shifted so the smallest becomes 1.
Skeleton skeleton_from_swc(const SwcFile& file);
// SWC text, numbered 1..N in Skeleton::parent_first_order(); `header` lines
// are written as comments. `renumbered`, when given, receives old id -> new.
// Numbers use the shortest text that reads back to the same double.
std::string skeleton_to_swc(const Skeleton& skeleton, const std::string& header,
                            std::map<int64_t, int64_t>* renumbered = nullptr);

}  // namespace vxr::annotate
