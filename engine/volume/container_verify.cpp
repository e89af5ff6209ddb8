#include "volume/container_verify.h"

#include <cstring>

#include "volume/container_io.h"
#include "volume/container_layout.h"

namespace vxr {

VerifyReport verify_container(const std::string& path) {
  VerifyReport rep;
  auto file = ContainerFile::open_read(path);
  if (!file) {
    rep.problems.push_back(file.status().message());
    return rep;
  }
  auto size_r = file->size();
  if (!size_r) {
    rep.problems.push_back(size_r.status().message());
    return rep;
  }
  const uint64_t size = *size_r;
  std::vector<uint8_t> head(std::min<uint64_t>(size, vxc::kMaxHeaderBytes));
  if (Status s = file->read_at(head.data(), head.size(), 0); !s) {
    rep.problems.push_back(s.message());
    return rep;
  }
  uint64_t header_bytes = 0;
  auto layout_r = parse_header(head, path, &header_bytes);
  if (!layout_r) {
    rep.problems.push_back("header: " + layout_r.status().message());
    return rep;
  }
  const ContainerLayout& L = *layout_r;
  uint64_t header_sum;
  std::memcpy(&header_sum, head.data() + header_bytes - 8, 8);

  // Footer.
  vxc::Footer f;
  bool footer_ok = false;
  if (size >= header_bytes + sizeof f + sizeof(vxc::IndexHeader) && file->read_at(&f, sizeof f, size - sizeof f)) {
    if (std::memcmp(f.magic, vxc::kFooterMagic, 8) != 0)
      rep.problems.push_back("footer: missing (unfinished or damaged conversion)");
    else if (f.footer_checksum != vxc::checksum(&f, 48))
      rep.problems.push_back("footer: fails its checksum");
    else if (f.file_bytes != size || f.header_checksum != header_sum || f.index_offset < header_bytes ||
             f.index_offset > size ||
             f.chunk_count > size / sizeof(vxc::IndexEntry) ||
             f.index_bytes != sizeof(vxc::IndexHeader) + f.chunk_count * sizeof(vxc::IndexEntry) ||
             f.index_offset + f.index_bytes + sizeof f != size)
      rep.problems.push_back("footer: describes a different file (size, header or index position)");
    else
      footer_ok = true;
  } else {
    rep.problems.push_back("footer: file too short to hold one");
  }

  auto check_entry = [&](const vxc::IndexEntry& e, uint64_t limit) {
    ++rep.chunks_checked;
    if (Status s = check_chunk_record(*file, L, e, limit); !s) {
      std::string msg = s.message();
      const std::string prefix = path + ": ";
      if (msg.rfind(prefix, 0) == 0) msg = msg.substr(prefix.size());
      rep.problems.push_back("chunk " + msg);
    }
  };

  if (footer_ok) {
    if (f.chunk_count != L.total_chunks())
      rep.problems.push_back("index: lists " + std::to_string(f.chunk_count) + " chunks, the pyramid needs " +
                             std::to_string(L.total_chunks()));
    // Streamed in bounded memory. The index is complete and sorted, so entry
    // i must name the chunk at position i: that also rules out duplicates.
    const bool positions = f.chunk_count == L.total_chunks();
    auto scan = scan_index(*file, f.index_offset, f.chunk_count, [&](uint64_t i, const vxc::IndexEntry& e) {
      const ChunkKey k = key_of(e);
      if (!L.contains(k)) {
        rep.problems.push_back("index: entry " + std::to_string(i) + " names a chunk outside the volume");
        return;
      }
      if (positions && !(L.key_at(i) == k)) {
        rep.problems.push_back("index: entry " + std::to_string(i) + " names " + describe_key(k) + " where " +
                               describe_key(L.key_at(i)) + " belongs (damaged, duplicated or out of order)");
        return;
      }
      if (e.offset < header_bytes || e.offset > f.index_offset || e.stored_size > f.index_offset - e.offset ||
          f.index_offset - e.offset - e.stored_size < sizeof(vxc::RecordHeader)) {
        rep.problems.push_back("chunk " + describe_key(k) + ": index entry points outside the chunk area");
        return;
      }
      check_entry(e, f.index_offset);
    });
    if (!scan) {
      rep.problems.push_back("index: " + scan.status().message());
      return rep;
    }
    if (std::memcmp(scan->header.magic, vxc::kIndexMagic, 8) != 0 || scan->header.count != f.chunk_count)
      rep.problems.insert(rep.problems.begin(), "index: header is damaged");
    if (scan->checksum != f.index_checksum) rep.problems.insert(rep.problems.begin(), "index: fails its checksum");
    return rep;
  }

  // No usable footer: walk the chunk records in file order.
  uint64_t off = header_bytes;
  uint64_t intact = 0;
  while (off < size) {
    auto rec = read_record_header(*file, off, size);
    if (!rec) {
      if (off + 8 <= size) {
        char magic[8];
        if (file->read_at(magic, 8, off) && std::memcmp(magic, vxc::kIndexMagic, 8) == 0) break;  // reached the index
      }
      rep.problems.push_back("chunk record at offset " + std::to_string(off) +
                             " is damaged; records after it cannot be located without the footer");
      break;
    }
    const size_t before = rep.problems.size();
    check_entry(entry_from_record(*rec, off), size);
    if (rep.problems.size() == before) ++intact;
    off += sizeof(vxc::RecordHeader) + rec->stored_size;
  }
  rep.problems.push_back("scan without footer: " + std::to_string(intact) + " chunk records intact");
  return rep;
}

}  // namespace vxr
