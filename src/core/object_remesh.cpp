#include "semantic_exploration/core/object_remesh.hpp"

#include <algorithm>
#include <filesystem>
#include <regex>
#include <vector>

#include "semantic_exploration/core/object_mesh.hpp"
#include "semantic_exploration/core/tsdf_io.hpp"

namespace semexp {

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
  std::sort(tsdfs.begin(), tsdfs.end());
  fs::create_directories(out, ec);
  if (ec) return fail("cannot create " + out.string() + ": " + ec.message());
  int written = 0;
  for (const fs::path& path : tsdfs) {
    std::string why;
    const auto map = loadTsdf(path.string(), &why);
    if (!map) return fail(why);
    fs::path ply = out / path.filename();
    ply.replace_extension(".ply");
    if (!writePly(objectMesh(*map, gate, fragment_gap_m), ply.string(), &why)) return fail(why);
    ++written;
  }
  if (!fs::equivalent(in, out, ec)) {
    fs::copy_file(index, out / "objects.json", fs::copy_options::overwrite_existing, ec);
    if (ec) return fail("cannot copy objects.json to " + out.string() + ": " + ec.message());
  }
  return written;
}

}  // namespace semexp
