// CSV exports of the store's analysis results, for spreadsheets and scripts:
// RFC 4180 (comma separated, header row, fields with , " or newlines quoted,
// "\n" line ends). Positions are volume coordinates (voxels); lengths are in
// the VoxelSpace unit named in the header.
#pragma once

#include <string>
#include <vector>

#include "annotate/annotations.h"

namespace vxr::annotate {

std::string csv_field(const std::string& s);  // quoted only when it must be

// id,class,r,g,b,a,x,y,z,timepoint,x_<unit>,y_<unit>,z_<unit>
std::string markers_csv(const std::vector<Marker>& markers, const VoxelSpace& space);
// class,count (classes in name order), optionally only markers at `timepoint` (< 0: all).
std::string counts_csv(const std::vector<Marker>& markers, int64_t timepoint = -1);
// id,label,timepoint,ax,ay,az,bx,by,bz,length_<unit>
std::string measurements_csv(const std::vector<Measurement>& measurements, const VoxelSpace& space);
// track,name,step,marker,timepoint,x,y,z,step_length_<unit>: one row per
// marker in time order; step_length is the distance from the previous step
// (empty on the first). Markers missing from `markers` are skipped.
std::string tracks_csv(const std::vector<Track>& tracks, const std::vector<Marker>& markers, const VoxelSpace& space);

}  // namespace vxr::annotate
