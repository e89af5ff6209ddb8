#include "xr/openxr/actions.h"

#include <cstring>
#include <vector>

namespace vxr::xr {
namespace {

enum class Side { kBoth, kLeft, kRight };

struct Binding {
  const char* action;  // "grip", "aim", "grab", "trigger", "thumbstick", "menu", "stick_click", "pick",
                       // "finish", "haptic"
  const char* path;    // under /user/hand/{left,right}
  Side side = Side::kBoth;
};

struct Profile {
  const char* path;
  std::vector<Binding> bindings;
};

// One table per controller family (what each physical control means to vxr).
// Pick and finish belong to the tool hand (right); a controller without face
// buttons gives them its trackpad click and right menu button, and keeps the
// left menu button for cycling tools.
const std::vector<Profile>& profiles() {
  static const std::vector<Profile> p = {
      {"/interaction_profiles/khr/simple_controller",
       {{"grip", "/input/grip/pose"}, {"aim", "/input/aim/pose"}, {"grab", "/input/select/click"},
        {"menu", "/input/menu/click"}, {"haptic", "/output/haptic"}}},
      {"/interaction_profiles/oculus/touch_controller",
       {{"grip", "/input/grip/pose"}, {"aim", "/input/aim/pose"}, {"grab", "/input/squeeze/value"},
        {"trigger", "/input/trigger/value"}, {"thumbstick", "/input/thumbstick"},
        {"menu", "/input/menu/click", Side::kLeft}, {"stick_click", "/input/thumbstick/click"},
        {"pick", "/input/a/click", Side::kRight}, {"finish", "/input/b/click", Side::kRight},
        {"haptic", "/output/haptic"}}},
      {"/interaction_profiles/htc/vive_controller",
       {{"grip", "/input/grip/pose"}, {"aim", "/input/aim/pose"}, {"grab", "/input/squeeze/click"},
        {"trigger", "/input/trigger/value"}, {"thumbstick", "/input/trackpad"},
        {"menu", "/input/menu/click", Side::kLeft}, {"stick_click", "/input/trackpad/click", Side::kLeft},
        {"pick", "/input/trackpad/click", Side::kRight}, {"finish", "/input/menu/click", Side::kRight},
        {"haptic", "/output/haptic"}}},
      {"/interaction_profiles/valve/index_controller",
       {{"grip", "/input/grip/pose"}, {"aim", "/input/aim/pose"}, {"grab", "/input/squeeze/value"},
        {"trigger", "/input/trigger/value"}, {"thumbstick", "/input/thumbstick"},
        {"menu", "/input/b/click", Side::kLeft}, {"stick_click", "/input/thumbstick/click"},
        {"pick", "/input/a/click", Side::kRight}, {"finish", "/input/b/click", Side::kRight},
        {"haptic", "/output/haptic"}}},
      {"/interaction_profiles/microsoft/motion_controller",
       {{"grip", "/input/grip/pose"}, {"aim", "/input/aim/pose"}, {"grab", "/input/squeeze/click"},
        {"trigger", "/input/trigger/value"}, {"thumbstick", "/input/thumbstick"},
        {"menu", "/input/menu/click", Side::kLeft}, {"stick_click", "/input/thumbstick/click"},
        {"pick", "/input/trackpad/click", Side::kRight}, {"finish", "/input/menu/click", Side::kRight},
        {"haptic", "/output/haptic"}}},
  };
  return p;
}

}  // namespace

Pose to_pose(const XrPosef& p) {
  return {glm::dquat(p.orientation.w, p.orientation.x, p.orientation.y, p.orientation.z),
          glm::dvec3(p.position.x, p.position.y, p.position.z)};
}

Status XrActions::create(XrInstance instance, XrErrors& errors) {
  VXR_XR_CALL(errors, xrStringToPath, (instance, "/user/hand/left", &hands_[kLeft]));
  VXR_XR_CALL(errors, xrStringToPath, (instance, "/user/hand/right", &hands_[kRight]));

  XrActionSetCreateInfo sci{XR_TYPE_ACTION_SET_CREATE_INFO};
  std::strcpy(sci.actionSetName, "volume");
  std::strcpy(sci.localizedActionSetName, "Volume");
  VXR_XR_CALL(errors, xrCreateActionSet, (instance, &sci, &set_));

  struct Def {
    XrAction* action;
    const char* name;
    const char* label;
    XrActionType type;
  };
  const Def defs[] = {
      {&grip_, "grip_pose", "Hand pose", XR_ACTION_TYPE_POSE_INPUT},
      {&aim_, "aim_pose", "Pointer pose", XR_ACTION_TYPE_POSE_INPUT},
      {&grab_, "grab", "Grab volume", XR_ACTION_TYPE_FLOAT_INPUT},
      {&trigger_, "trigger", "Trigger", XR_ACTION_TYPE_FLOAT_INPUT},
      {&thumbstick_, "thumbstick", "Fly", XR_ACTION_TYPE_VECTOR2F_INPUT},
      {&menu_, "menu", "Menu", XR_ACTION_TYPE_BOOLEAN_INPUT},
      {&stick_click_, "stick_click", "Teleport", XR_ACTION_TYPE_BOOLEAN_INPUT},
      {&pick_, "pick", "Pick node", XR_ACTION_TYPE_BOOLEAN_INPUT},
      {&finish_, "finish", "Finish branch", XR_ACTION_TYPE_BOOLEAN_INPUT},
      {&haptic_, "haptic", "Haptic pulse", XR_ACTION_TYPE_VIBRATION_OUTPUT},
  };
  for (const Def& d : defs) {
    XrActionCreateInfo aci{XR_TYPE_ACTION_CREATE_INFO};
    aci.actionType = d.type;
    std::strcpy(aci.actionName, d.name);
    std::strcpy(aci.localizedActionName, d.label);
    aci.countSubactionPaths = 2;
    aci.subactionPaths = hands_.data();
    VXR_XR_CALL(errors, xrCreateAction, (set_, &aci, d.action));
  }

  auto action_of = [&](const std::string& n) -> XrAction {
    if (n == "grip") return grip_;
    if (n == "aim") return aim_;
    if (n == "grab") return grab_;
    if (n == "trigger") return trigger_;
    if (n == "thumbstick") return thumbstick_;
    if (n == "menu") return menu_;
    if (n == "stick_click") return stick_click_;
    if (n == "pick") return pick_;
    if (n == "finish") return finish_;
    return haptic_;
  };
  for (const Profile& p : profiles()) {
    std::vector<XrActionSuggestedBinding> suggested;
    for (const Binding& b : p.bindings) {
      for (int h = 0; h < 2; ++h) {
        if ((b.side == Side::kLeft && h == kRight) || (b.side == Side::kRight && h == kLeft)) continue;
        XrPath path = XR_NULL_PATH;
        const std::string full = std::string(h == kLeft ? "/user/hand/left" : "/user/hand/right") + b.path;
        VXR_XR_CALL(errors, xrStringToPath, (instance, full.c_str(), &path));
        suggested.push_back({action_of(b.action), path});
      }
    }
    XrPath profile = XR_NULL_PATH;
    VXR_XR_CALL(errors, xrStringToPath, (instance, p.path, &profile));
    XrInteractionProfileSuggestedBinding sb{XR_TYPE_INTERACTION_PROFILE_SUGGESTED_BINDING};
    sb.interactionProfile = profile;
    sb.countSuggestedBindings = static_cast<uint32_t>(suggested.size());
    sb.suggestedBindings = suggested.data();
    VXR_XR_CALL(errors, xrSuggestInteractionProfileBindings, (instance, &sb));
  }
  return Status::ok();
}

Status XrActions::attach(XrSession session, XrErrors& errors) {
  XrSessionActionSetsAttachInfo ai{XR_TYPE_SESSION_ACTION_SETS_ATTACH_INFO};
  ai.countActionSets = 1;
  ai.actionSets = &set_;
  VXR_XR_CALL(errors, xrAttachSessionActionSets, (session, &ai));
  for (int h = 0; h < 2; ++h) {
    XrActionSpaceCreateInfo ci{XR_TYPE_ACTION_SPACE_CREATE_INFO};
    ci.subactionPath = hands_[h];
    ci.poseInActionSpace.orientation.w = 1.0f;
    ci.action = grip_;
    VXR_XR_CALL(errors, xrCreateActionSpace, (session, &ci, &grip_space_[h]));
    ci.action = aim_;
    VXR_XR_CALL(errors, xrCreateActionSpace, (session, &ci, &aim_space_[h]));
  }
  return Status::ok();
}

Status XrActions::read(XrSession session, XrSpace base, XrTime time, InputState& out, XrErrors& errors) {
  XrActiveActionSet active{set_, XR_NULL_PATH};
  XrActionsSyncInfo sync{XR_TYPE_ACTIONS_SYNC_INFO};
  sync.countActiveActionSets = 1;
  sync.activeActionSets = &active;
  VXR_XR_CALL(errors, xrSyncActions, (session, &sync));
  for (int h = 0; h < 2; ++h) {
    HandInput& hand = out.hands[h];
    XrActionStateGetInfo gi{XR_TYPE_ACTION_STATE_GET_INFO};
    gi.subactionPath = hands_[h];

    gi.action = grab_;
    XrActionStateFloat f{XR_TYPE_ACTION_STATE_FLOAT};
    VXR_XR_CALL(errors, xrGetActionStateFloat, (session, &gi, &f));
    hand.grab = f.isActive ? f.currentState : 0.0;
    gi.action = trigger_;
    f = {XR_TYPE_ACTION_STATE_FLOAT};
    VXR_XR_CALL(errors, xrGetActionStateFloat, (session, &gi, &f));
    hand.trigger = f.isActive ? f.currentState : 0.0;
    gi.action = thumbstick_;
    XrActionStateVector2f v{XR_TYPE_ACTION_STATE_VECTOR2F};
    VXR_XR_CALL(errors, xrGetActionStateVector2f, (session, &gi, &v));
    hand.thumbstick = v.isActive ? glm::dvec2(v.currentState.x, v.currentState.y) : glm::dvec2(0.0);
    auto button = [&](XrAction action, bool& out) -> Status {
      gi.action = action;
      XrActionStateBoolean b{XR_TYPE_ACTION_STATE_BOOLEAN};
      VXR_XR_CALL(errors, xrGetActionStateBoolean, (session, &gi, &b));
      out = b.isActive && b.currentState;
      return Status::ok();
    };
    VXR_RETURN_IF_ERROR(button(menu_, hand.menu));
    VXR_RETURN_IF_ERROR(button(stick_click_, hand.stick_click));
    VXR_RETURN_IF_ERROR(button(pick_, hand.primary));
    VXR_RETURN_IF_ERROR(button(finish_, hand.secondary));
    gi.action = grip_;
    XrActionStatePose p{XR_TYPE_ACTION_STATE_POSE};
    VXR_XR_CALL(errors, xrGetActionStatePose, (session, &gi, &p));

    hand.tracked = false;
    if (p.isActive) {
      XrSpaceLocation loc{XR_TYPE_SPACE_LOCATION};
      VXR_XR_CALL(errors, xrLocateSpace, (grip_space_[h], base, time, &loc));
      const XrSpaceLocationFlags need = XR_SPACE_LOCATION_POSITION_VALID_BIT | XR_SPACE_LOCATION_ORIENTATION_VALID_BIT;
      if ((loc.locationFlags & need) == need) {
        hand.tracked = true;
        hand.grip = to_pose(loc.pose);
      }
      loc = {XR_TYPE_SPACE_LOCATION};
      VXR_XR_CALL(errors, xrLocateSpace, (aim_space_[h], base, time, &loc));
      if ((loc.locationFlags & need) == need) hand.aim = to_pose(loc.pose);
    }
  }
  return Status::ok();
}

Status XrActions::haptic(XrSession session, Hand hand, double amplitude, double seconds, XrErrors& errors) {
  XrHapticActionInfo hi{XR_TYPE_HAPTIC_ACTION_INFO};
  hi.action = haptic_;
  hi.subactionPath = hands_[hand];
  XrHapticVibration vib{XR_TYPE_HAPTIC_VIBRATION};
  vib.amplitude = static_cast<float>(amplitude);
  vib.duration = static_cast<XrDuration>(seconds * 1e9);
  vib.frequency = XR_FREQUENCY_UNSPECIFIED;
  VXR_XR_CALL(errors, xrApplyHapticFeedback, (session, &hi, reinterpret_cast<const XrHapticBaseHeader*>(&vib)));
  return Status::ok();
}

std::string XrActions::current_profile(XrInstance instance, XrSession session, XrErrors& errors) {
  XrInteractionProfileState st{XR_TYPE_INTERACTION_PROFILE_STATE};
  if (XR_FAILED(xrGetCurrentInteractionProfile(session, hands_[kRight], &st)) || st.interactionProfile == XR_NULL_PATH)
    return "";
  char buf[XR_MAX_PATH_LENGTH];
  uint32_t n = 0;
  if (XR_FAILED(xrPathToString(instance, st.interactionProfile, sizeof buf, &n, buf))) return "";
  (void)errors;
  return buf;
}

void XrActions::detach() {
  for (int h = 0; h < 2; ++h) {
    if (grip_space_[h]) xrDestroySpace(grip_space_[h]);
    if (aim_space_[h]) xrDestroySpace(aim_space_[h]);
    grip_space_[h] = aim_space_[h] = XR_NULL_HANDLE;
  }
}

}  // namespace vxr::xr
