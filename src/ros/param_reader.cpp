// ParamReader: typed values out of a parameter tree, each read recorded for
// list_params. The loaders that use it are in params.cpp.
#include "semantic_exploration/ros/params.hpp"

#include <ros/node_handle.h>

#include <cmath>
#include <cstdio>
#include <sstream>

namespace semexp_ros {

using semexp::ConfigError;
using XmlRpc::XmlRpcValue;

namespace {

const char* typeName(const XmlRpcValue& v) {
  switch (v.getType()) {
    case XmlRpcValue::TypeBoolean: return "bool";
    case XmlRpcValue::TypeInt: return "int";
    case XmlRpcValue::TypeDouble: return "double";
    case XmlRpcValue::TypeString: return "string";
    case XmlRpcValue::TypeArray: return "list";
    case XmlRpcValue::TypeStruct: return "map";
    default: return "unset";
  }
}

[[noreturn]] void wrongType(const std::string& path, const XmlRpcValue& v, const char* want) {
  throw ConfigError(path, std::string("must be ") + want + ", got " + typeName(v));
}

std::string text(double v) {
  char buf[40];
  std::snprintf(buf, sizeof(buf), "%.17g", v);
  return buf;
}
std::string text(int v) { return std::to_string(v); }
std::string text(bool v) { return v ? "true" : "false"; }
std::string text(const std::string& v) { return "\"" + v + "\""; }
template <typename T>
std::string text(const std::vector<T>& v) {
  std::string out = "[";
  for (const auto& e : v) out += (out.size() > 1 ? ", " : "") + text(e);
  return out + "]";
}

double asDouble(const std::string& path, const XmlRpcValue& v) {
  XmlRpcValue& m = const_cast<XmlRpcValue&>(v);  // XmlRpc's conversion operators are non-const
  if (v.getType() == XmlRpcValue::TypeDouble) return static_cast<double>(m);
  if (v.getType() == XmlRpcValue::TypeInt) return static_cast<int>(m);
  wrongType(path, v, "a number");
}

// The value of a parameter that must have XmlRpc type `type` (`want` names it in the error).
template <typename T>
T asType(const std::string& path, const XmlRpcValue& v, XmlRpcValue::Type type, const char* want) {
  if (v.getType() != type) wrongType(path, v, want);
  return static_cast<T>(const_cast<XmlRpcValue&>(v));  // XmlRpc's conversion operators are non-const
}

}  // namespace

ParamReader ParamReader::fromNodeHandle(const ros::NodeHandle& pnh) {
  XmlRpcValue root;
  if (!pnh.getParam(pnh.getNamespace(), root) || root.getType() != XmlRpcValue::TypeStruct) root = XmlRpcValue();
  return ParamReader(root);
}

const XmlRpcValue* ParamReader::find(const std::string& path) const {
  const XmlRpcValue* cur = &root_;
  std::stringstream ss(path);
  std::string key;
  while (std::getline(ss, key, '/')) {
    if (key.empty()) continue;
    if (cur->getType() != XmlRpcValue::TypeStruct) return nullptr;
    XmlRpcValue& m = const_cast<XmlRpcValue&>(*cur);
    if (!m.hasMember(key)) return nullptr;
    cur = &m[key];
  }
  return cur;
}

bool ParamReader::has(const std::string& path) const { return find(path) != nullptr; }

void ParamReader::record(const std::string& path, std::string default_text) const {
  if (log_) log_->push_back({path, std::move(default_text)});
}

void ParamReader::get(const std::string& path, double& out) const {
  record(path, text(out));
  if (const auto* v = find(path)) out = asDouble(path, *v);
}

void ParamReader::get(const std::string& path, int& out) const {
  record(path, text(out));
  if (const auto* v = find(path)) out = asType<int>(path, *v, XmlRpcValue::TypeInt, "an integer");
}

void ParamReader::get(const std::string& path, bool& out) const {
  record(path, text(out));
  if (const auto* v = find(path)) out = asType<bool>(path, *v, XmlRpcValue::TypeBoolean, "true or false");
}

void ParamReader::get(const std::string& path, std::string& out) const {
  record(path, text(out));
  if (const auto* v = find(path)) out = asType<std::string>(path, *v, XmlRpcValue::TypeString, "a string");
}

void ParamReader::get(const std::string& path, std::vector<std::string>& out) const {
  record(path, text(out));
  const auto* v = find(path);
  if (!v) return;
  if (v->getType() != XmlRpcValue::TypeArray) wrongType(path, *v, "a list of strings");
  XmlRpcValue& m = const_cast<XmlRpcValue&>(*v);
  std::vector<std::string> r;
  for (int i = 0; i < m.size(); ++i)
    r.push_back(asType<std::string>(path, m[i], XmlRpcValue::TypeString, "a list of strings"));
  out = r;
}

void ParamReader::get(const std::string& path, std::vector<double>& out) const {
  record(path, text(out));
  const auto* v = find(path);
  if (!v) return;
  if (v->getType() != XmlRpcValue::TypeArray) wrongType(path, *v, "a list of numbers");
  XmlRpcValue& m = const_cast<XmlRpcValue&>(*v);
  std::vector<double> r;
  for (int i = 0; i < m.size(); ++i) r.push_back(asDouble(path, m[i]));
  out = r;
}

void ParamReader::getAtLeast(const std::string& path, double& out, double min_value, const std::string& unit) const {
  double v = out;
  get(path, v);
  if (!(v >= min_value)) {
    char buf[64];
    std::snprintf(buf, sizeof(buf), "must be >= %g %s", min_value, unit.c_str());
    throw ConfigError(path, buf);
  }
  out = v;
}

void ParamReader::getPositiveAtMost(const std::string& path, double& out, double max_value,
                                    const std::string& unit) const {
  get(path, out);
  if (!(out > 0 && out <= max_value))
    throw ConfigError(path, "must be in (0, " + std::to_string(static_cast<int>(max_value)) + "] " + unit);
}

}  // namespace semexp_ros
