#pragma once
/// @file tsdf_io.hpp
/// Saving and loading an object TSDF (the fixed-point layout), so that its
/// mesh can be extracted again offline under another MeshGate.
///
/// The file holds a text header of "key value" lines (the format's name and
/// version, then the TsdfParams), "blocks N", then N binary blocks in index
/// order (by z, then y, then x; one map always gives the same bytes), little
/// endian: the block index as 3 int32, a has_negative byte, and block_size^3
/// voxels of 10 bytes each (int16 sdf_q, uint16 weight_q, uint16
/// min_distance_mm, uint8 foreground_q, 3 x uint8 rgb), x fastest. A loaded
/// map holds exactly the saved voxels. has_negative is Block::has_negative:
/// set once a voxel of the block was given a negative SDF, and kept (ray
/// casts step over blocks without it); a loader sets it too wherever a voxel
/// is negative, so a writer that clears it cannot hide a surface.

#include <memory>
#include <string>

#include "semantic_exploration/core/tsdf.hpp"

namespace semexp {

/// Writes `map` to `path` atomically. False (and *error set) on failure.
bool saveTsdf(const TsdfMap& map, const std::string& path, std::string* error = nullptr);

/// Reads a map saveTsdf wrote; null (and *error set, naming what is wrong)
/// if the file is missing, of another format or version, or truncated.
std::unique_ptr<TsdfMap> loadTsdf(const std::string& path, std::string* error = nullptr);

}  // namespace semexp
