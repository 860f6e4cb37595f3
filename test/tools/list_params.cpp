// Lists every parameter the nodes' loaders (src/ros/params.cpp, allLoaders())
// read, with its default in code, so that test/python/test_config_consistency.py
// compares the YAML files with what the code reads instead of with a pattern
// that could drift from it.
//
// Input (stdin): one XML-RPC <value> holding the parameter tree (a YAML file
// as rosparam would load it). Output: "loader\t<name>" per loader run, then
// "param\t<path>\t<default>" per parameter read (first read wins). A loader
// that rejects the tree (e.g. the detector without a model) has read all its
// parameters by then: its error goes to stderr and the listing goes on.
#include <iostream>
#include <iterator>
#include <set>
#include <string>

#include "semantic_exploration/ros/params.hpp"

int main() {
  const std::string xml((std::istreambuf_iterator<char>(std::cin)), std::istreambuf_iterator<char>());
  int offset = 0;
  const auto at = xml.find("<value>");
  if (at == std::string::npos) {
    std::cerr << "list_params: no <value> on stdin\n";
    return 2;
  }
  offset = static_cast<int>(at);
  const XmlRpc::XmlRpcValue root(xml, &offset);
  if (root.getType() != XmlRpc::XmlRpcValue::TypeStruct) {
    std::cerr << "list_params: the input is not a parameter map\n";
    return 2;
  }
  semexp_ros::ParamReader p(root);
  std::vector<semexp_ros::ParamRead> reads;
  p.recordReads(&reads);
  for (const auto& [name, load] : semexp_ros::allLoaders()) {
    std::cout << "loader\t" << name << "\n";
    try {
      load(p);
    } catch (const std::exception& e) {
      std::cerr << name << ": " << e.what() << "\n";
    }
  }
  std::set<std::string> seen;
  for (const auto& r : reads)
    if (seen.insert(r.path).second) std::cout << "param\t" << r.path << "\t" << r.default_text << "\n";
  return 0;
}
