#include "semantic_exploration/core/object_remesh.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <vector>

#include "semantic_exploration/core/object_mesh.hpp"
#include "semantic_exploration/core/tsdf_io.hpp"

namespace semexp {

bool readSavedMeshSettings(const std::string& dir, ObjectMapConfig& c, std::string* error) {
  const std::string index = (std::filesystem::path(dir) / "objects.json").string();
  std::ifstream f(index);
  if (!f) {
    if (error) *error = "cannot read " + index;
    return false;
  }
  const std::string json((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  const std::size_t gate = json.find("\"mesh_gate\"");
  if (gate == std::string::npos) {
    if (error) *error = index + " records no mesh_gate (saved by an older build)";
    return false;
  }
  // Each key once, inside the mesh_gate object that ObjectMap::save writes last.
  ObjectMapConfig read = c;
  const std::pair<const char*, double*> keys[] = {
      {"mesh_min_weight", &read.mesh_min_weight},         {"mesh_max_sdf_std_m", &read.mesh_max_sdf_std_m},
      {"mesh_min_foreground", &read.mesh_min_foreground}, {"mesh_fragment_gap_m", &read.mesh_fragment_gap_m},
      {"sigma_min_m", &read.depth_noise.sigma_min_m},     {"s_per_m", &read.depth_noise.s_per_m},
      {"sigma_max_m", &read.depth_noise.sigma_max_m}};
  for (const auto& [key, value] : keys) {
    const std::regex re(std::string("\"") + key + "\":\\s*([-+0-9.eE]+)");
    std::smatch m;
    const std::string rest = json.substr(gate);
    if (!std::regex_search(rest, m, re)) {
      if (error) *error = index + ": mesh_gate lacks " + key;
      return false;
    }
    try {
      *value = std::stod(m[1].str());
    } catch (const std::exception&) {
      if (error) *error = index + ": mesh_gate's " + key + " is not a number";
      return false;
    }
  }
  c = read;
  return true;
}

int remeshSavedObjects(const std::string& in_dir, const std::string& out_dir, const MeshGate& gate,
                       double fragment_gap_m, std::string* error) {
  namespace fs = std::filesystem;
  const auto fail = [&](const std::string& why) {
    if (error) *error = why;
    return -1;
  };
  std::error_code ec;
  const fs::path in = fs::absolute(in_dir), out = fs::absolute(out_dir);
  const fs::path index = in / "objects.json";
  if (!fs::is_regular_file(index, ec)) return fail("no objects.json in " + in.string() + " (not a saved object map)");
  std::vector<fs::path> tsdfs;
  const std::regex tsdf_name("object_[0-9]+_.*\\.tsdf");
  for (const auto& entry : fs::directory_iterator(in, ec))
    if (std::regex_match(entry.path().filename().string(), tsdf_name)) tsdfs.push_back(entry.path());
  if (ec) return fail("cannot list " + in.string() + ": " + ec.message());
  if (tsdfs.empty()) return fail("no object TSDF in " + in.string() + " (save with object_map/save_tsdf true)");
  if (!(gate.min_foreground >= 0.5f && gate.min_foreground < 1.f))
    return fail("the foreground bound must lie in [0.5, 1)");
  if (fs::exists(out, ec) && fs::equivalent(in, out, ec))
    return fail("the output directory is the input: the saved meshes would be overwritten");
  std::sort(tsdfs.begin(), tsdfs.end());
  fs::create_directories(out, ec);
  if (ec) return fail("cannot create " + out.string() + ": " + ec.message());
  int written = 0;
  std::vector<fs::path> meshes;
  for (const fs::path& path : tsdfs) {
    std::string why;
    const auto map = loadTsdf(path.string(), &why);
    if (!map) return fail(why);
    fs::path ply = out / path.filename();
    ply.replace_extension(".ply");
    if (!writePly(objectMesh(*map, gate, fragment_gap_m), ply.string(), &why)) return fail(why);
    meshes.push_back(ply);
    ++written;
  }
  // Meshes left in out_dir by an earlier run on another map would read as objects of this one.
  const std::regex mesh_name("object_[0-9]+_.*\\.ply");
  for (const auto& entry : fs::directory_iterator(out, ec)) {
    if (!std::regex_match(entry.path().filename().string(), mesh_name)) continue;
    if (std::find(meshes.begin(), meshes.end(), entry.path()) == meshes.end()) fs::remove(entry.path(), ec);
  }
  fs::copy_file(index, out / "objects.json", fs::copy_options::overwrite_existing, ec);
  if (ec) return fail("cannot copy objects.json to " + out.string() + ": " + ec.message());
  return written;
}

}  // namespace semexp
