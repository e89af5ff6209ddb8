#include "annotate/skeleton.h"

#include <algorithm>
#include <set>

namespace vxr::annotate {

const SkeletonNode* Skeleton::find(int64_t node_id) const {
  auto it = nodes_.find(node_id);
  return it == nodes_.end() ? nullptr : &it->second;
}

Status Skeleton::missing(int64_t node_id) const {
  return not_found("skeleton " + std::to_string(id_) + " has no node " + std::to_string(node_id));
}

Result<int64_t> Skeleton::add_node(SkeletonNode node) {
  if (node.id == 0) node.id = next_node_id();
  if (node.id < 0) return invalid_argument("node id " + std::to_string(node.id) + " must be positive");
  if (nodes_.count(node.id)) {
    return invalid_argument("skeleton " + std::to_string(id_) + " already has a node " + std::to_string(node.id));
  }
  if (node.parent != kNoParent && !nodes_.count(node.parent)) return missing(node.parent);
  if (!(node.radius >= 0.0)) return invalid_argument("node radius must be >= 0");
  nodes_[node.id] = node;
  return node.id;
}

Status Skeleton::move_node(int64_t node_id, const Vec3& pos) {
  auto it = nodes_.find(node_id);
  if (it == nodes_.end()) return missing(node_id);
  it->second.pos = pos;
  return Status::ok();
}

Status Skeleton::set_radius(int64_t node_id, double radius) {
  auto it = nodes_.find(node_id);
  if (it == nodes_.end()) return missing(node_id);
  if (!(radius >= 0.0)) return invalid_argument("node radius must be >= 0");
  it->second.radius = radius;
  return Status::ok();
}

Status Skeleton::set_type(int64_t node_id, int type) {
  auto it = nodes_.find(node_id);
  if (it == nodes_.end()) return missing(node_id);
  it->second.type = type;
  return Status::ok();
}

std::multimap<int64_t, int64_t> Skeleton::child_index() const {
  std::multimap<int64_t, int64_t> index;  // parent -> child, children in ascending id (map order)
  for (const auto& [id, n] : nodes_)
    if (n.parent != kNoParent) index.emplace(n.parent, id);
  return index;
}

std::vector<int64_t> Skeleton::children(int64_t node_id) const {
  std::vector<int64_t> out;
  for (const auto& [id, n] : nodes_)
    if (n.parent == node_id) out.push_back(id);
  return out;
}

std::vector<int64_t> Skeleton::roots() const {
  std::vector<int64_t> out;
  for (const auto& [id, n] : nodes_)
    if (n.parent == kNoParent) out.push_back(id);
  return out;
}

std::vector<int64_t> Skeleton::subtree(int64_t node_id) const {
  if (!nodes_.count(node_id)) return {};
  const auto index = child_index();
  std::vector<int64_t> out{node_id};
  for (size_t i = 0; i < out.size(); ++i) {
    auto [b, e] = index.equal_range(out[i]);
    for (auto it = b; it != e; ++it) out.push_back(it->second);
  }
  return out;
}

std::vector<int64_t> Skeleton::parent_first_order() const {
  const auto index = child_index();
  std::vector<int64_t> out;
  out.reserve(nodes_.size());
  std::vector<int64_t> stack;
  const auto roots_list = roots();
  for (auto r = roots_list.rbegin(); r != roots_list.rend(); ++r) stack.push_back(*r);
  while (!stack.empty()) {
    const int64_t id = stack.back();
    stack.pop_back();
    out.push_back(id);
    auto [b, e] = index.equal_range(id);
    std::vector<int64_t> kids;
    for (auto it = b; it != e; ++it) kids.push_back(it->second);
    for (auto k = kids.rbegin(); k != kids.rend(); ++k) stack.push_back(*k);  // ascending ids pop first
  }
  return out;  // nodes on a parent cycle are unreachable from a root and left out; validate() reports them
}

Status Skeleton::delete_node(int64_t node_id) {
  auto it = nodes_.find(node_id);
  if (it == nodes_.end()) return missing(node_id);
  const int64_t up = it->second.parent;
  for (auto& [id, n] : nodes_)
    if (n.parent == node_id) n.parent = up;
  nodes_.erase(it);
  return Status::ok();
}

Status Skeleton::delete_subtree(int64_t node_id) {
  if (!nodes_.count(node_id)) return missing(node_id);
  for (int64_t id : subtree(node_id)) nodes_.erase(id);
  return Status::ok();
}

Status Skeleton::reparent(int64_t node_id, int64_t new_parent) {
  auto it = nodes_.find(node_id);
  if (it == nodes_.end()) return missing(node_id);
  if (new_parent != kNoParent) {
    if (!nodes_.count(new_parent)) return missing(new_parent);
    // Walk up from the new parent: meeting node_id means it is a descendant.
    for (int64_t p = new_parent; p != kNoParent; p = nodes_.at(p).parent) {
      if (p == node_id) {
        return invalid_argument("cannot attach node " + std::to_string(node_id) + " under " +
                                std::to_string(new_parent) + ": that node is in its own subtree (a cycle)");
      }
    }
  }
  it->second.parent = new_parent;
  return Status::ok();
}

Result<Skeleton> Skeleton::split(int64_t node_id) {
  if (!nodes_.count(node_id)) return missing(node_id);
  Skeleton part(0, name_ + " (split at " + std::to_string(node_id) + ")");
  for (int64_t id : subtree(node_id)) {
    part.nodes_[id] = nodes_.at(id);
    nodes_.erase(id);
  }
  part.nodes_.at(node_id).parent = kNoParent;
  return part;
}

Result<std::map<int64_t, int64_t>> Skeleton::merge(Skeleton& other, int64_t other_node, int64_t attach_to) {
  if (&other == this) return invalid_argument("cannot merge a skeleton into itself");
  if (!other.nodes_.count(other_node)) return other.missing(other_node);
  if (attach_to != kNoParent && !nodes_.count(attach_to)) return missing(attach_to);
  VXR_RETURN_IF_ERROR(other.validate());
  // Re-root: reverse the parent links on the path other_node -> its root.
  int64_t prev = kNoParent;
  for (int64_t cur = other_node; cur != kNoParent;) {
    const int64_t up = other.nodes_.at(cur).parent;
    other.nodes_.at(cur).parent = prev;
    prev = cur;
    cur = up;
  }
  std::map<int64_t, int64_t> renumber;
  int64_t next = next_node_id();
  for (const auto& [id, n] : other.nodes_) renumber[id] = next++;
  for (const auto& [id, n] : other.nodes_) {
    SkeletonNode moved = n;
    moved.id = renumber.at(id);
    moved.parent = n.parent == kNoParent ? kNoParent : renumber.at(n.parent);
    nodes_[moved.id] = moved;
  }
  nodes_.at(renumber.at(other_node)).parent = attach_to;
  other.nodes_.clear();
  return renumber;
}

Status Skeleton::validate() const {
  for (const auto& [id, n] : nodes_) {
    if (id <= 0 || n.id != id)
      return internal_error("skeleton " + std::to_string(id_) + ": bad node id " + std::to_string(id));
    if (n.parent != kNoParent && !nodes_.count(n.parent)) {
      return corrupt("skeleton " + std::to_string(id_) + ": node " + std::to_string(id) + " names parent " +
                     std::to_string(n.parent) + ", which does not exist");
    }
  }
  // Every node must reach a root; colour nodes as their chain is proven.
  std::set<int64_t> proven;
  for (const auto& [id, n] : nodes_) {
    std::vector<int64_t> chain;
    std::set<int64_t> on_chain;
    int64_t cur = id;
    while (cur != kNoParent && !proven.count(cur)) {
      if (!on_chain.insert(cur).second) {
        return corrupt("skeleton " + std::to_string(id_) + ": node " + std::to_string(cur) +
                       " is its own ancestor (a cycle)");
      }
      chain.push_back(cur);
      cur = nodes_.at(cur).parent;
    }
    proven.insert(chain.begin(), chain.end());
  }
  return Status::ok();
}

}  // namespace vxr::annotate
