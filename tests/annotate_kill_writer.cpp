// Helper for the kill-9 test (annotate_test.cpp): writes annotations into a
// store forever and, after each write call returns, reports it on stdout as
// one line (a single write(2), so a line is either whole in the pipe or not
// there). The test kills this process with SIGKILL at random moments and
// checks every reported write survived.
//   annotate_kill_writer STORE FIRST_SEQ
//   m <marker id> <seq>         marker at (seq, 2 seq, 3 seq), class c<seq % 4>, timepoint seq % 5
//   n <skeleton> <node> <seq>   node at (seq, 0, 1) radius seq/10, child of the previous node
//   c <card id> <seq>           card note "card <seq>", a snapshot of seq+9 bytes
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <string>

#include "annotate/annotation_store.h"

using namespace vxr::annotate;

namespace {
void ack(const std::string& line) {
  const std::string out = line + "\n";
  if (::write(1, out.data(), out.size()) != static_cast<ssize_t>(out.size())) std::_Exit(4);
}
}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: annotate_kill_writer STORE FIRST_SEQ\n");
    return 2;
  }
  auto store = AnnotationStore::open(argv[1], true);
  if (!store.is_ok()) {
    std::fprintf(stderr, "%s\n", store.status().message().c_str());
    return 1;
  }
  AnnotationStore& s = **store;
  // One skeleton shared by every run: reuse it, extend from its newest node.
  Id sk = 0;
  int64_t last = kNoParent;
  auto list = s.skeletons();
  if (!list.is_ok()) return 1;
  if (!list->empty()) {
    sk = list->front().id;
    auto loaded = s.skeleton(sk);
    if (!loaded.is_ok()) return 1;
    if (loaded->size()) last = loaded->nodes().rbegin()->first;
  } else {
    auto made = s.add_skeleton(Skeleton(0, "kill test"));
    if (!made.is_ok()) return 1;
    sk = *made;
  }
  for (long seq = std::atol(argv[2]);; ++seq) {
    const double d = static_cast<double>(seq);
    switch (seq % 3) {
      case 0: {
        Marker m;
        m.cls = "c" + std::to_string(seq % 4);
        m.pos = {d, 2 * d, 3 * d};
        m.timepoint = static_cast<uint32_t>(seq % 5);
        auto id = s.add_marker(m);
        if (!id.is_ok()) return 1;
        ack("m " + std::to_string(*id) + " " + std::to_string(seq));
        break;
      }
      case 1: {
        SkeletonNode n;
        n.pos = {d, 0, 1};
        n.radius = d / 10;
        n.type = 3;
        n.parent = last;
        auto id = s.add_node(sk, n);
        if (!id.is_ok()) return 1;
        last = *id;
        ack("n " + std::to_string(sk) + " " + std::to_string(*id) + " " + std::to_string(seq));
        break;
      }
      default: {
        Card c;
        c.title = "kill";
        c.note = "card " + std::to_string(seq);
        c.snapshot_png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
        c.snapshot_png.resize(static_cast<size_t>(seq) + 9, static_cast<uint8_t>(seq));
        auto id = s.add_card(c);
        if (!id.is_ok()) return 1;
        ack("c " + std::to_string(*id) + " " + std::to_string(seq));
      }
    }
  }
}
