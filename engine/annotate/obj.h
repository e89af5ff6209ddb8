// Wavefront OBJ meshes (segmented surfaces: a tissue, its cells, their
// substructures) read tolerantly: v and f (polygons, negative indices), o and
// g as the hierarchy (each g hangs below the o before it), usemtl colours from
// the mtllib's Kd. What a reader can skip (vt, vn, s, l, comments, unknown
// keywords) is skipped with a warning naming the line; what would draw a
// wrong picture (an index past the vertices, a non-finite number) is an error
// naming the file and line. Normals are not read: faces are shaded flat from
// their own geometry.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "annotate/annotations.h"
#include "core/status.h"

namespace vxr::annotate {

struct MeshPart {
  std::string name;
  int parent = -1;                // index into Mesh::parts; -1: top level (an `o`)
  uint32_t first_triangle = 0;    // its triangles are [first, first + count)
  uint32_t triangle_count = 0;
};

struct MeshMaterial {
  std::string name;
  std::array<float, 3> color{0.8f, 0.8f, 0.8f};  // Kd, linear RGB
};

struct Mesh {
  std::vector<Vec3> positions;
  std::vector<std::array<uint32_t, 3>> triangles;  // counter-clockwise as the file gave them
  std::vector<uint32_t> triangle_material;         // index into materials, per triangle
  std::vector<MeshMaterial> materials;             // [0] is the default grey
  std::vector<MeshPart> parts;                     // in file order; each triangle lies in exactly one
};

struct ObjResult {
  Mesh mesh;
  std::vector<std::string> warnings;  // "<file>:<line>: ..."
};

// `source` names the file in messages; `mtl_dir` is where mtllib files are looked for ("" : not read).
Result<ObjResult> parse_obj(const std::string& text, const std::string& source, const std::string& mtl_dir);
Result<ObjResult> read_obj(const std::string& path);

}  // namespace vxr::annotate
