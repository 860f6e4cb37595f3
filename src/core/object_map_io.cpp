#include "semantic_exploration/core/atomic_file.hpp"
#include "semantic_exploration/core/object_map.hpp"
#include "semantic_exploration/core/object_mesh.hpp"
#include "semantic_exploration/core/object_remesh.hpp"
#include "semantic_exploration/core/tsdf_io.hpp"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <ostream>
#include <regex>

// ObjectMap::save: meshes and the objects.json index.

namespace semexp {

namespace {

std::string jsonEscape(const std::string& s) {
  std::string out;
  for (const char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    if (static_cast<unsigned char>(c) < 0x20) continue;
    out += c;
  }
  return out;
}

std::string vec(const Eigen::Vector3d& v) {
  char buf[96];
  std::snprintf(buf, sizeof(buf), "[%.4f, %.4f, %.4f]", v.x(), v.y(), v.z());
  return buf;
}

}  // namespace

TsdfSummary ObjectMap::summarize(const MappedObject& object, double d_obj_m) const {
  const TsdfSummary s = object.tsdf.summarize(d_obj_m);
  return s.voxel_count > 0 ? s : object.tsdf.summarize(d_obj_m, true);
}

Mesh ObjectMap::mesh(const MappedObject& object) const {
  return objectMesh(object.tsdf, config_.meshGate(), config_.mesh_fragment_gap_m);
}

std::vector<std::string> ObjectMap::save(const std::string& directory, double d_obj_m, std::string* error) const {
  std::vector<std::string> files;
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::create_directories(directory, ec);
  if (ec) {
    if (error) *error = "cannot create " + directory + ": " + ec.message();
    return files;
  }
  const fs::path dir = fs::absolute(directory);
  std::string json = "{\"objects\": [";
  bool first = true;
  for (const auto& kv : objects_) {
    const MappedObject& o = *kv.second;
    const std::string name = "object_" + std::to_string(o.id) + "_" + o.class_name + ".ply";
    const std::string path = (dir / name).string();
    std::string why;
    if (!writePly(mesh(o), path, &why)) {
      if (error) *error = why;
      return files;
    }
    files.push_back(path);
    std::string tsdf_entry;
    if (config_.save_tsdf) {
      const std::string tsdf_name = name.substr(0, name.size() - 4) + ".tsdf";
      if (!saveTsdf(o.tsdf, (dir / tsdf_name).string(), &why)) {
        if (error) *error = why;
        return files;
      }
      files.push_back((dir / tsdf_name).string());
      tsdf_entry = ", \"tsdf\": \"" + jsonEscape(tsdf_name) + "\"";
    }
    const TsdfSummary s = summarize(o, d_obj_m);
    char buf[320];
    std::snprintf(buf, sizeof(buf),
                  "\"resolution_m\": %.4f, \"voxel_count\": %zu, \"observed_fraction\": %.4f, "
                  "\"detection_count\": %u, \"undetected_count\": %u, \"weight_sum\": %.1f, ",
                  o.resolution_m, s.voxel_count, s.observed_fraction, o.detection_count, o.undetected_count,
                  s.weight_sum);
    json += std::string(first ? "" : ",") + "\n  {\"id\": " + std::to_string(o.id) +
            ", \"class_id\": " + std::to_string(o.class_id) + ", \"class_name\": \"" + jsonEscape(o.class_name) +
            "\", " + buf + "\"bbox_min\": " + vec(s.bbox_min_W) + ", \"bbox_max\": " + vec(s.bbox_max_W) +
            ", \"centroid\": " + vec(s.centroid_W) + ", \"mesh\": \"" + jsonEscape(name) + "\"" + tsdf_entry + "}";
    first = false;
  }
  // The gate the meshes were extracted under, last, for the record and for remesh_objects.
  char tail[64];  // %.6g: any d_obj_m fits
  std::snprintf(tail, sizeof(tail), "\n], \"d_obj_m\": %.6g,\n", d_obj_m);
  json += std::string(tail) + "\"mesh_gate\": " + meshGateJson(config_) + "}\n";
  const std::string index = (dir / "objects.json").string();
  try {
    writeFileAtomically(index, [&json](std::ostream& f) { f << json; });
  } catch (const std::exception& e) {
    if (error) *error = e.what();
    return files;
  }
  files.push_back(index);
  // Meshes (and TSDFs) of objects merged away since an earlier save into this directory would read as
  // objects still there: once the new index is in place, they go.
  const std::regex mesh_name("object_[0-9]+_.*\\.(ply|tsdf)");
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    if (!std::regex_match(name, mesh_name) || !entry.is_regular_file(ec)) continue;
    if (std::find(files.begin(), files.end(), entry.path().string()) != files.end()) continue;
    std::error_code rm;
    if (!fs::remove(entry.path(), rm) && error) *error = "cannot remove the stale " + entry.path().string();
  }
  return files;
}

}  // namespace semexp
