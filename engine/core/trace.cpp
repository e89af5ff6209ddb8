#include "core/trace.h"

#include "core/output_file.h"

#include <atomic>
#include <fstream>
#include <mutex>
#include <sstream>
#include <thread>
#include <vector>

namespace vxr::trace {
namespace {

struct Event {
  std::string name;
  std::string track;
  uint64_t tid;
  double start_us;
  double dur_us;
};

std::atomic<bool> g_enabled{false};
std::mutex g_mutex;
std::vector<Event> g_events;
const auto g_origin = std::chrono::steady_clock::now();

std::string json_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    if (static_cast<unsigned char>(c) < 0x20) continue;
    out += c;
  }
  return out;
}

}  // namespace

bool enabled() { return g_enabled.load(std::memory_order_relaxed); }

void start() {
#ifdef VXR_PROFILE
  g_enabled = true;
#endif
}

double now_us() {
  return std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - g_origin).count();
}

void add_complete(const std::string& name, const char* track, double start_us, double dur_us) {
  if (!enabled()) return;
  const uint64_t tid = std::hash<std::thread::id>{}(std::this_thread::get_id()) & 0xffff;
  std::lock_guard<std::mutex> lock(g_mutex);
  g_events.push_back({name, track, tid, start_us, dur_us});
}

Status write(const std::string& path) {
  std::ostringstream os;
  os << "{\"traceEvents\":[\n";
  os << R"({"name":"process_name","ph":"M","pid":1,"args":{"name":"vxr CPU"}},)" << "\n";
  os << R"({"name":"process_name","ph":"M","pid":2,"args":{"name":"vxr GPU"}})";
  {
    std::lock_guard<std::mutex> lock(g_mutex);
    for (const Event& e : g_events) {
      const bool gpu = e.track == "gpu";
      os << ",\n{\"name\":\"" << json_escape(e.name) << "\",\"cat\":\"" << e.track
         << "\",\"ph\":\"X\",\"pid\":" << (gpu ? 2 : 1) << ",\"tid\":" << (gpu ? 0 : e.tid)
         << ",\"ts\":" << e.start_us << ",\"dur\":" << e.dur_us << "}";
    }
  }
  os << "\n],\"displayTimeUnit\":\"ms\"}\n";
  return write_file_atomically(path, os.str());
}

}  // namespace vxr::trace
