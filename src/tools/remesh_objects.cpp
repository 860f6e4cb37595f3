// remesh_objects: extracts the meshes of a saved object map again under
// another mesh gate, from the TSDFs the object map saves with
// object_map/save_tsdf true. The flags are the object_map parameters of the
// same names (config/semantic.yaml); unset ones keep the gate the saved
// meshes were extracted under (objects.json's mesh_gate), or the core
// defaults where the index records none.
//
//   rosrun semantic_exploration remesh_objects IN_DIR OUT_DIR
//       [--mesh_min_foreground P] [--mesh_min_weight W] [--mesh_max_sdf_std_m E]
//       [--depth_noise/sigma_min_m S] [--depth_noise/s_per_m Q] [--depth_noise/sigma_max_m M]
//       [--mesh_fragment_gap_m G]
#include <iostream>
#include <map>
#include <string>

#include "semantic_exploration/core/config_error.hpp"
#include "semantic_exploration/core/object_map_config.hpp"
#include "semantic_exploration/core/object_remesh.hpp"

int main(int argc, char** argv) {
  const std::string usage =
      "usage: remesh_objects IN_DIR OUT_DIR [--mesh_min_foreground P] [--mesh_min_weight W] "
      "[--mesh_max_sdf_std_m E] [--depth_noise/sigma_min_m S] [--depth_noise/s_per_m Q] "
      "[--depth_noise/sigma_max_m M] [--mesh_fragment_gap_m G]\n";
  if (argc < 3 || (argc - 3) % 2 != 0) {
    std::cerr << usage;
    return 2;
  }
  semexp::ObjectMapConfig c;
  std::string why;
  if (semexp::readSavedMeshSettings(argv[1], c, &why))
    std::cout << "remesh_objects: starting from the saved gate (mesh_min_weight " << c.mesh_min_weight
              << ", mesh_max_sdf_std_m " << c.mesh_max_sdf_std_m << ", mesh_min_foreground " << c.mesh_min_foreground
              << ", mesh_fragment_gap_m " << c.mesh_fragment_gap_m << ", depth_noise " << c.depth_noise.sigma_min_m
              << " m / " << c.depth_noise.s_per_m << " 1/m / " << c.depth_noise.sigma_max_m << " m)\n";
  else
    std::cout << "remesh_objects: " << why << "; starting from the defaults\n";
  const std::map<std::string, double*> flags = {
      {"--mesh_min_foreground", &c.mesh_min_foreground},
      {"--mesh_min_weight", &c.mesh_min_weight},
      {"--mesh_max_sdf_std_m", &c.mesh_max_sdf_std_m},
      {"--depth_noise/sigma_min_m", &c.depth_noise.sigma_min_m},
      {"--depth_noise/s_per_m", &c.depth_noise.s_per_m},
      {"--depth_noise/sigma_max_m", &c.depth_noise.sigma_max_m},
      {"--mesh_fragment_gap_m", &c.mesh_fragment_gap_m}};
  for (int i = 3; i < argc; i += 2) {
    const auto it = flags.find(argv[i]);
    std::size_t used = 0;
    try {
      if (it != flags.end()) *it->second = std::stod(argv[i + 1], &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (it == flags.end() || used != std::string(argv[i + 1]).size()) {
      std::cerr << "remesh_objects: " << (it == flags.end() ? "unknown flag " : "not a number for ") << argv[i]
                << "\n" << usage;
      return 2;
    }
  }
  try {
    c.validate();
  } catch (const semexp::ConfigError& e) {
    std::cerr << "remesh_objects: " << e.what() << "\n";
    return 2;
  }
  std::string error;
  const int n = semexp::remeshSavedObjects(argv[1], argv[2], c, &error);
  if (n < 0) {
    std::cerr << "remesh_objects: " << error << "\n";
    return 1;
  }
  std::cout << "remesh_objects: " << n << " meshes written to " << argv[2] << "\n";
  return 0;
}
