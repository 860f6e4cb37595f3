#include "semantic_exploration/core/class_table.hpp"

#include <algorithm>
#include <cmath>
#include <set>

namespace semexp {

void ClassTable::validate(const std::string& ns) const {
  require(!names.empty(), ns + "names", "must list at least one class");
  std::set<std::string> seen;
  for (const auto& n : names) {
    require(!n.empty(), ns + "names", "class names must not be empty");
    require(seen.insert(n).second, ns + "names", "duplicate class '" + n + "'");
  }
  require(names.size() < 65535, ns + "names", "at most 65534 classes (16-bit ids)");
  require(!of_interest.empty(), ns + "of_interest", "must list at least one class of interest");
  for (const auto& n : of_interest)
    require(seen.count(n) > 0, ns + "of_interest", "unknown class '" + n + "' (not in " + ns + "names)");
  for (const auto& kv : resolution_m) {
    require(seen.count(kv.first) > 0, ns + "resolution_m", "unknown class '" + kv.first + "'");
    require(std::isfinite(kv.second) && kv.second > 0, ns + "resolution_m",
            "resolution of '" + kv.first + "' must be > 0 m");
  }
  require(std::isfinite(default_resolution_m) && default_resolution_m > 0, ns + "default_resolution_m",
          "must be > 0 m");
}

int ClassTable::id(const std::string& n) const {
  const auto it = std::find(names.begin(), names.end(), n);
  return it == names.end() ? 0 : static_cast<int>(it - names.begin()) + 1;
}

std::string ClassTable::name(int i) const {
  return (i >= 1 && i <= static_cast<int>(names.size())) ? names[i - 1] : std::string();
}

bool ClassTable::isOfInterest(int i) const {
  const std::string n = name(i);
  return !n.empty() && std::find(of_interest.begin(), of_interest.end(), n) != of_interest.end();
}

double ClassTable::resolution(int i) const {
  const auto it = resolution_m.find(name(i));
  return it == resolution_m.end() ? default_resolution_m : it->second;
}

}  // namespace semexp
