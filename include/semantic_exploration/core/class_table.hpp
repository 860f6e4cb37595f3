#pragma once
/// @file class_table.hpp
/// Semantic classes known to the system, the classes of interest and the
/// object-map resolution of each class.

#include <map>
#include <string>
#include <vector>

#include "semantic_exploration/core/config_error.hpp"

namespace semexp {

struct ClassTable {
  /// Known class names; class id = index + 1 (0 means "no / unknown class").
  std::vector<std::string> names{"chair",  "table",   "sofa",     "bed",      "cabinet",
                                 "plant",  "tv_monitor", "backpack", "keyboard", "cushion"};
  /// Classes whose instances get an object submap (paper: "chair").
  std::vector<std::string> of_interest{"chair"};
  /// Object-map voxel size per class, m. Classes not listed use default_resolution_m.
  std::map<std::string, double> resolution_m{{"chair", 0.02}};
  double default_resolution_m = 0.02;  ///< m

  void validate(const std::string& ns = "classes/") const;

  /// Class id of `name`, 0 if unknown.
  int id(const std::string& name) const;
  /// Name of class `id`, "" if out of range.
  std::string name(int id) const;
  bool isOfInterest(int id) const;
  /// Object-map voxel size of class `id`, m.
  double resolution(int id) const;
};

}  // namespace semexp
