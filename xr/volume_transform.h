// Where the volume sits in the target's reference space, and the ray caster
// camera for one view of it.
//
// The ray caster's world space is the volume's physical units centred on the
// volume (render/camera.h); the XR reference space is metres, +y up. The
// transform between them is a similarity (rotation, uniform scale,
// translation) kept in double so repeated grabs do not drift.
#pragma once

#include "render/camera.h"
#include "volume/dense_volume.h"
#include "xr/frame_target.h"

namespace vxr::xr {

struct VolumeTransform {
  glm::dvec3 position{0.0};                     // reference-space position of the volume centre
  glm::dquat orientation{1.0, 0.0, 0.0, 0.0};   // volume axes in the reference space
  double scale = 1.0;                           // metres per volume unit

  glm::dvec3 to_reference(const glm::dvec3& volume_point) const {
    return orientation * (scale * volume_point) + position;
  }
  glm::dvec3 to_volume(const glm::dvec3& reference_point) const {
    return (glm::conjugate(orientation) * (reference_point - position)) / scale;
  }
};

// The starting placement: the volume's longest diagonal `size_m` metres,
// centred at `centre`, its +z axis up (+y) and its -y face towards +z.
VolumeTransform default_volume_transform(const VolumePlacement& placement, double size_m = 0.35,
                                         glm::dvec3 centre = {0.0, 1.6, -0.5});

// The ray caster camera for `view` (pose and off-axis fov) with the volume at `t`.
Camera camera_for_view(const ViewSpec& view, const VolumeTransform& t);

// The transform that makes a view from `head` see what the ray caster camera
// `camera` (volume frame) sees: the camera's eye lands on the head and its
// view direction and up on the head's -z and +y. `scale` (metres per volume
// unit) is free, since a uniform scale about the eye leaves the picture
// as it is (only stereo depth and the hands' reach change with it).
VolumeTransform transform_placing_camera(const Camera& camera, const Pose& head, double scale);

// The head between `views`: the mean of their positions, the first view's
// orientation (the eyes of a head-mounted display look the same way).
Pose head_of_views(const std::vector<ViewSpec>& views);

// Two eyes `ipd_m` apart on the head's x axis, sharing `fov` and size.
std::vector<ViewSpec> stereo_views(const Pose& head, double ipd_m, const Fov& fov, uint32_t width,
                                   uint32_t height);

}  // namespace vxr::xr
