// Window pixels <-> volume voxels for the desktop tools and the annotation
// overlay, for each view the window shows: the mono view, or either eye of
// side-by-side stereo (the left eye at x0 = 0, the right one at x0 = its
// width). A click picks on the plane through the orbit centre that faces the
// view. No window system or ImGui here.
#pragma once

#include <array>
#include <optional>
#include <vector>

#include "render/camera.h"
#include "xr/frame_target.h"
#include "xr/volume_transform.h"

namespace vxr::xr {

struct WindowView {
  ViewSpec view;    // pose (reference space), off-axis fov, size in pixels
  double x0 = 0.0;  // its left edge in window pixels
};

// The view of `views` holding window pixel x (the last one right of its left edge); nullopt left of all.
std::optional<size_t> view_at(const std::vector<WindowView>& views, double x);

// The voxel that window pixel (x, y) shows on the plane through `focus`
// (world units in the volume's frame) facing the view; nullopt when the
// pixel's ray runs parallel to that plane or away from it.
std::optional<std::array<double, 3>> voxel_under(const WindowView& v, const VolumeTransform& t,
                                                 const VolumePlacement& placement, const glm::dvec3& focus,
                                                 double x, double y);

// Where voxel `voxel` appears in the window (pixels); nullopt behind the eye.
std::optional<std::array<double, 2>> project_voxel(const WindowView& v, const VolumeTransform& t,
                                                   const VolumePlacement& placement,
                                                   const std::array<double, 3>& voxel);

// Of `voxels`, the one drawn nearest window pixel (x, y), if within
// `radius_px` pixels: a click on a drawn node picks it whatever its depth.
std::optional<size_t> nearest_on_screen(const WindowView& v, const VolumeTransform& t, const VolumePlacement& placement,
                                        const std::vector<std::array<double, 3>>& voxels, double x, double y,
                                        double radius_px);

// The volume axis (0, 1, 2) nearest the view's direction: a box dragged on
// the screen spans the whole volume along it.
int depth_axis(const WindowView& v, const VolumeTransform& t);

// `voxel` moved to the near (0) or far (dims) face of the volume along `axis`.
std::array<double, 3> on_volume_face(std::array<double, 3> voxel, int axis, const VolumePlacement& placement,
                                     bool far);

}  // namespace vxr::xr
