#include "semantic_exploration/core/object_remesh.hpp"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <vector>

#include "semantic_exploration/core/atomic_file.hpp"
#include "semantic_exploration/core/object_mesh.hpp"
#include "semantic_exploration/core/tsdf_io.hpp"

namespace semexp {

namespace {

constexpr const char* kGateKey = "\"mesh_gate\": ";

bool readText(const std::string& path, std::string& text) {
  std::ifstream f(path);
  if (!f) return false;
  text.assign(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
  return true;
}

}  // namespace

std::string meshGateJson(const ObjectMapConfig& c) {
  char buf[400];
  std::snprintf(buf, sizeof(buf),
                "{\"mesh_min_weight\": %.17g, \"mesh_max_sdf_std_m\": %.17g, \"mesh_min_foreground\": %.17g, "
                "\"mesh_fragment_gap_m\": %.17g, \"depth_noise\": {\"sigma_min_m\": %.17g, \"s_per_m\": %.17g, "
                "\"sigma_max_m\": %.17g}}",
                c.mesh_min_weight, c.mesh_max_sdf_std_m, c.mesh_min_foreground, c.mesh_fragment_gap_m,
                c.depth_noise.sigma_min_m, c.depth_noise.s_per_m, c.depth_noise.sigma_max_m);
  return buf;
}

bool readSavedMeshSettings(const std::string& dir, ObjectMapConfig& c, std::string* error) {
  const std::string index = (std::filesystem::path(dir) / "objects.json").string();
  std::string json;
  if (!readText(index, json)) {
    if (error) *error = "cannot read " + index;
    return false;
  }
  // The mesh_gate object as meshGateJson writes it: from its key to the "}}" that closes depth_noise and it.
  const std::size_t begin = json.rfind(kGateKey);
  const std::size_t end = begin == std::string::npos ? begin : json.find("}}", begin);
  if (end == std::string::npos) {
    if (error) *error = index + " records no mesh_gate (saved by an older build)";
    return false;
  }
  const std::string gate = json.substr(begin, end + 2 - begin);
  ObjectMapConfig read = c;
  const std::pair<const char*, double*> keys[] = {
      {"mesh_min_weight", &read.mesh_min_weight},         {"mesh_max_sdf_std_m", &read.mesh_max_sdf_std_m},
      {"mesh_min_foreground", &read.mesh_min_foreground}, {"mesh_fragment_gap_m", &read.mesh_fragment_gap_m},
      {"sigma_min_m", &read.depth_noise.sigma_min_m},     {"s_per_m", &read.depth_noise.s_per_m},
      {"sigma_max_m", &read.depth_noise.sigma_max_m}};
  for (const auto& [key, value] : keys) {
    const std::regex re(std::string("\"") + key + "\":\\s*([-+0-9.eE]+)");
    std::smatch m;
    if (!std::regex_search(gate, m, re)) {
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

int remeshSavedObjects(const std::string& in_dir, const std::string& out_dir, const ObjectMapConfig& c,
                       std::string* error) {
  namespace fs = std::filesystem;
  const auto fail = [&](const std::string& why) {
    if (error) *error = why;
    return -1;
  };
  try {
    c.validate();
  } catch (const ConfigError& e) {
    return fail(e.what());
  }
  std::error_code ec;
  const fs::path in = fs::absolute(in_dir), out = fs::absolute(out_dir);
  std::string index;
  if (!readText((in / "objects.json").string(), index))
    return fail("no objects.json in " + in.string() + " (not a saved object map)");
  std::vector<fs::path> tsdfs;
  const std::regex tsdf_name("object_[0-9]+_.*\\.tsdf");
  for (const auto& entry : fs::directory_iterator(in, ec))
    if (std::regex_match(entry.path().filename().string(), tsdf_name)) tsdfs.push_back(entry.path());
  if (ec) return fail("cannot list " + in.string() + ": " + ec.message());
  if (tsdfs.empty()) return fail("no object TSDF in " + in.string() + " (save with object_map/save_tsdf true)");
  std::sort(tsdfs.begin(), tsdfs.end());
  std::vector<fs::path> meshes;
  for (const fs::path& path : tsdfs) meshes.push_back(out / path.filename().replace_extension(".ply"));
  if (fs::exists(out, ec)) {
    if (fs::equivalent(in, out, ec))
      return fail("the output directory is the input: the saved meshes would be overwritten");
    // A mesh of an object this map has no TSDF of would read as one of its objects; it is another map's.
    const std::regex mesh_name("object_[0-9]+_.*\\.ply");
    for (const auto& entry : fs::directory_iterator(out, ec))
      if (std::regex_match(entry.path().filename().string(), mesh_name) &&
          std::find(meshes.begin(), meshes.end(), entry.path()) == meshes.end())
        return fail(out.string() + " holds " + entry.path().filename().string() +
                    ", a mesh of another map: choose another directory");
    if (ec) return fail("cannot list " + out.string() + ": " + ec.message());
  }
  fs::create_directories(out, ec);
  if (ec) return fail("cannot create " + out.string() + ": " + ec.message());
  for (std::size_t i = 0; i < tsdfs.size(); ++i) {
    std::string why;
    const auto map = loadTsdf(tsdfs[i].string(), &why);
    if (!map) return fail(why);
    if (!writePly(objectMesh(*map, c.meshGate(), c.mesh_fragment_gap_m), meshes[i].string(), &why)) return fail(why);
  }
  // The index with the gate these meshes were extracted under (added where an older index has none).
  const std::size_t gate = index.rfind(kGateKey), close = index.rfind('}');
  if (close == std::string::npos) return fail(in.string() + "/objects.json is not a JSON object");
  const std::string head = gate != std::string::npos ? index.substr(0, gate) : index.substr(0, close) + ",\n";
  const std::string rewritten = head + kGateKey + meshGateJson(c) + "}\n";
  try {
    writeFileAtomically((out / "objects.json").string(), [&](std::ostream& f) { f << rewritten; });
  } catch (const std::exception& e) {
    return fail(e.what());
  }
  return static_cast<int>(tsdfs.size());
}

}  // namespace semexp
