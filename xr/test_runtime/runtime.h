// vxr's OpenXR test runtime: a small, deterministic OpenXR runtime that the
// Khronos loader loads like any other (XR_RUNTIME_JSON=<build>/xr/test_runtime/
// vxr_test_runtime.json), so CI can run vxr's real OpenXR path, with the
// XR_APILAYER_LUNARG_core_validation layer in front of it, on lavapipe.
//
// What it implements is what vxr uses: instance and system (one head-mounted
// display), XR_KHR_vulkan_enable2 (it creates the Vulkan instance/device the
// app asks for and picks a CPU device when there is one),
// XR_KHR_composition_layer_depth, sessions with the full state machine,
// reference and action spaces, swapchains backed by VkImages on the app's
// device, the frame loop with deterministic display times (frame i is shown
// at 1 s + i * 1/90 s), actions for the five controller profiles vxr binds
// (each action answers from the physical control its binding names:
// squeeze, trigger, thumbstick, menu, thumbstick/trackpad click, a/x, b/y,
// as the pose script's hands give them, xr/script.h), and haptics (counted).
//
// Driving it (environment):
//   VXR_TEST_RUNTIME_SCRIPT=file.json  pose script (xr/script.h) plus:
//       "session_loss_at_frame": N   queue LOSS_PENDING at frame N (once per process)
//       "fail": [{"function": "xrCreateSwapchain", "call": 2, "result": "XR_ERROR_RUNTIME_FAILURE"}]
//       "no_headset": true           xrGetSystem -> XR_ERROR_FORM_FACTOR_UNAVAILABLE
//       "no_stage": true             only LOCAL and VIEW reference spaces
//       "no_depth": true             do not offer XR_KHR_composition_layer_depth
//       "no_srgb": true              offer UNORM colour swapchains only (eye dumps hold the renderer's bytes)
//       "profile": "/interaction_profiles/valve/index_controller"
//       "dump_frames": [30]          write those frames' eye images as PNG
//   VXR_TEST_RUNTIME_FAIL=function:k:XR_ERROR_...  fail the k-th call (1-based) of function
//   VXR_TEST_RUNTIME_DUMP_DIR=dir      where dump_frames go (frameNNNNNN_left/right.png)
//   VXR_TEST_RUNTIME_REPORT=file.json  written when a session is destroyed: frames, states,
//                                      haptic pulses, the interaction profile
//   VXR_TEST_RUNTIME_CALL_LOG=file     every xr* function the app called, one per line
//
// Process-wide counters (call counts for injected failures, "session lost
// once") live in environment variables, because the loader unloads the
// runtime library when the instance is destroyed.
#pragma once
