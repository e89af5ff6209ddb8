// Faults through the OpenXR path, run as a user runs vxr (a child process,
// so a crash is seen as a crash): every xr* function vxr calls is made to
// fail once by the test runtime; vxr must recover through its restart loop or
// exit 1 with a message naming the call, never crash, and leave nothing for
// Vulkan validation to report (leaked objects are reported at device
// teardown, and vxr exits 3 on any validation message).
#include <doctest/doctest.h>

#include <set>
#include <sstream>

#include "xr_test_util.h"

using namespace vxr;

namespace {

const char* kScript = R"({
  "view": {"width": 24, "height": 24},
  "keys": [{"frame": 0, "left": {"squeeze": 0}}, {"frame": 2, "left": {"squeeze": 1}}]})";

std::string vxr_view(const std::string& env, int frames = 3) {
  return "env " + env + " " + VXR_BINARY + " view --sample --xr --frames " + std::to_string(frames);
}

}  // namespace

TEST_CASE("openxr faults: an error injected at each xr* function vxr calls: recovery or a clear message") {
  const std::string dir = test::xr_out_dir("faults");
  test::use_test_runtime(dir, kScript);
  const std::string log = dir + "/calls.txt";
  const test::ChildResult clean = test::run_child(vxr_view("VXR_TEST_RUNTIME_CALL_LOG=" + log));
  INFO(clean.output);
  REQUIRE(clean.exit_code == 0);
  std::set<std::string> functions;
  std::istringstream in(test::read_text(log));
  for (std::string line; std::getline(in, line);)
    if (!line.empty()) functions.insert(line);
  // The calls a session of vxr makes (a sample; the log has them all).
  for (const char* f : {"xrCreateInstance", "xrGetSystem", "xrCreateVulkanInstanceKHR", "xrCreateVulkanDeviceKHR",
                        "xrCreateSession", "xrCreateSwapchain", "xrWaitFrame", "xrBeginFrame", "xrEndFrame",
                        "xrLocateViews", "xrSyncActions", "xrLocateSpace", "xrAcquireSwapchainImage",
                        "xrApplyHapticFeedback", "xrRequestExitSession", "xrEndSession", "xrDestroySession",
                        "xrSuggestInteractionProfileBindings"})
    CHECK_MESSAGE(functions.count(f) == 1, f << " was not called");
  MESSAGE(functions.size() << " xr* functions called by vxr view");

  int recovered = 0, reported = 0;
  for (const std::string& f : functions) {
    const test::ChildResult r = test::run_child(vxr_view("VXR_TEST_RUNTIME_FAIL=" + f + ":1:XR_ERROR_RUNTIME_FAILURE"));
    INFO("injected XR_ERROR_RUNTIME_FAILURE at the first " << f << ":\n" << r.output);
    CHECK(r.signal == 0);
    CHECK((r.exit_code == 0 || r.exit_code == 1));
    CHECK(r.output.find("Vulkan validation") == std::string::npos);
    if (r.exit_code == 1) {
      ++reported;
      CHECK(r.output.find("vxr: OpenXR: ") != std::string::npos);
      CHECK(r.output.find(" failed with XR_ERROR_") != std::string::npos);  // the loader may translate the code
    } else {
      ++recovered;
    }
  }
  MESSAGE(reported << " ended with a message, " << recovered << " carried on");
  CHECK(reported > 10);
  CHECK(test::core_validation_messages(dir).empty());
}

TEST_CASE("openxr faults: XR_ERROR_SESSION_LOST anywhere in the frame loop is recovered by the restart loop") {
  const std::string dir = test::xr_out_dir("session_lost");
  test::use_test_runtime(dir, kScript);
  for (const char* f : {"xrWaitFrame:3", "xrBeginFrame:3", "xrEndFrame:3", "xrLocateViews:2", "xrSyncActions:2",
                        "xrAcquireSwapchainImage:3", "xrReleaseSwapchainImage:3", "xrLocateSpace:2"}) {
    const test::ChildResult r =
        test::run_child(vxr_view(std::string("VXR_TEST_RUNTIME_FAIL=") + f + ":XR_ERROR_SESSION_LOST", 4));
    INFO("XR_ERROR_SESSION_LOST at " << f << ":\n" << r.output);
    CHECK(r.exit_code == 0);
    CHECK(r.output.find("4 frames rendered") != std::string::npos);
    CHECK(r.output.find("1 restart(s)") != std::string::npos);
  }
  // Lost on every try: gives up after the restart budget with a clear message.
  const test::ChildResult r = test::run_child(
      vxr_view("VXR_TEST_RUNTIME_FAIL=xrCreateSession:1:XR_ERROR_SESSION_LOST,xrCreateSession:2:XR_ERROR_SESSION_LOST,"
               "xrCreateSession:3:XR_ERROR_SESSION_LOST,xrCreateSession:4:XR_ERROR_SESSION_LOST"));
  INFO(r.output);
  CHECK(r.exit_code == 1);
  CHECK(r.output.find("lost 4 times; giving up") != std::string::npos);
  CHECK(test::core_validation_messages(dir).empty());
}
