// Skeleton: a traced tree (or forest) of nodes and the edits the tracing tool
// makes. Every edit either keeps the structure valid (each parent exists in
// this skeleton, no cycles) or changes nothing and says why. The store
// (annotation_store.h) loads a Skeleton, applies an edit and writes back the
// nodes that changed in one atomic batch.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "annotate/annotations.h"
#include "core/status.h"

namespace vxr::annotate {

class Skeleton {
 public:
  Skeleton() = default;
  Skeleton(Id id, std::string name) : id_(id), name_(std::move(name)) {}

  Id id() const { return id_; }
  void set_id(Id id) { id_ = id; }
  const std::string& name() const { return name_; }
  void set_name(std::string name) { name_ = std::move(name); }
  const std::map<int64_t, SkeletonNode>& nodes() const { return nodes_; }
  size_t size() const { return nodes_.size(); }
  const SkeletonNode* find(int64_t node_id) const;

  // Adds `node`; node.id 0 picks the next free id. The parent must already be
  // in the skeleton (or kNoParent). Returns the node's id.
  Result<int64_t> add_node(SkeletonNode node);
  Status move_node(int64_t node_id, const Vec3& pos);
  Status set_radius(int64_t node_id, double radius);
  Status set_type(int64_t node_id, int type);
  // Removes one node; its children are attached to its parent (or become
  // roots when it was a root), so no branch is lost.
  Status delete_node(int64_t node_id);
  // Removes a node and everything below it.
  Status delete_subtree(int64_t node_id);
  // Attaches `node_id` (with its subtree) under `new_parent`, or makes it a
  // root with kNoParent. Refused when new_parent lies inside that subtree.
  Status reparent(int64_t node_id, int64_t new_parent);
  // Detaches the subtree rooted at `node_id` and returns it as a new skeleton
  // (node ids kept, `node_id` becomes its root).
  Result<Skeleton> split(int64_t node_id);
  // Moves every node of `other` into this skeleton under fresh ids: the tree
  // of `other` holding `other_node` is re-rooted at it and hung below
  // `attach_to` (kNoParent: it stays a separate root). Returns other's old id
  // -> new id. `other` is left empty.
  Result<std::map<int64_t, int64_t>> merge(Skeleton& other, int64_t other_node, int64_t attach_to);

  // Ok when every parent exists here and no parent chain loops.
  Status validate() const;
  std::vector<int64_t> roots() const;
  std::vector<int64_t> children(int64_t node_id) const;
  // The node and all its descendants.
  std::vector<int64_t> subtree(int64_t node_id) const;
  // Depth-first, parents before children, roots and siblings by ascending id:
  // the order the SWC writer numbers nodes in.
  std::vector<int64_t> parent_first_order() const;
  int64_t next_node_id() const { return nodes_.empty() ? 1 : nodes_.rbegin()->first + 1; }

  // Bulk load (store, SWC import): no checks until validate().
  void insert_unchecked(const SkeletonNode& node) { nodes_[node.id] = node; }

 private:
  Status missing(int64_t node_id) const;
  std::multimap<int64_t, int64_t> child_index() const;

  Id id_ = 0;
  std::string name_;
  std::map<int64_t, SkeletonNode> nodes_;
};

}  // namespace vxr::annotate
