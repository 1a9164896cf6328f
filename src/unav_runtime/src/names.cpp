#include "unav_runtime/names.hpp"

#include <cctype>

#include "unav_runtime/errors.hpp"

namespace unav {
namespace {

bool is_name_char(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }

void validate_tokens(const std::string& name, const std::string& what) {
  // Every token between slashes: non-empty, [A-Za-z0-9_], not starting with a digit.
  size_t i = name.empty() || name[0] != '/' ? 0 : 1;
  if (name == "/") return;
  while (i <= name.size()) {
    const size_t end = name.find('/', i);
    const std::string tok = name.substr(i, end == std::string::npos ? std::string::npos : end - i);
    if (tok.empty()) throw NameError(what + " '" + name + "' is invalid: empty token ('//' or trailing '/')");
    if (std::isdigit(static_cast<unsigned char>(tok[0])))
      throw NameError(what + " '" + name + "' is invalid: token '" + tok + "' starts with a digit");
    for (char c : tok)
      if (!is_name_char(c))
        throw NameError(what + " '" + name + "' is invalid: character '" + std::string(1, c) +
                        "' is not allowed (use [A-Za-z0-9_] and '/')");
    if (end == std::string::npos) break;
    i = end + 1;
  }
}

}  // namespace

void validate_node_name(const std::string& name) {
  if (name.empty()) throw NameError("node name is empty");
  if (name.find('/') != std::string::npos) throw NameError("node name '" + name + "' must not contain '/'");
  validate_tokens(name, "node name");
}

std::string normalize_namespace(const std::string& ns) {
  if (ns.empty() || ns == "/") return "/";
  std::string out = ns[0] == '/' ? ns : "/" + ns;
  if (out.size() > 1 && out.back() == '/') out.pop_back();
  validate_tokens(out, "namespace");
  return out;
}

std::string resolve_topic_name(const std::string& name, const std::string& node_namespace,
                               const std::string& node_name) {
  if (name.empty()) throw NameError("topic name is empty");
  const std::string ns = normalize_namespace(node_namespace);
  const std::string prefix = ns == "/" ? "" : ns;
  std::string out;
  if (name[0] == '/') {
    out = name;
  } else if (name[0] == '~') {
    if (name.size() > 1 && name[1] != '/')
      throw NameError("topic name '" + name + "' is invalid: '~' must be followed by '/'");
    out = prefix + "/" + node_name + name.substr(1);
  } else {
    out = prefix + "/" + name;
  }
  if (out.find('~') != std::string::npos)
    throw NameError("topic name '" + name + "' is invalid: '~' is only allowed at the start");
  validate_tokens(out, "topic name");
  return out;
}

std::string apply_remaps(const std::string& resolved, const std::vector<RemapRule>& rules,
                         const std::string& node_namespace, const std::string& node_name) {
  for (const auto& r : rules) {
    if (!r.node.empty() && r.node != node_name) continue;
    if (r.from.rfind("__", 0) == 0) continue;  // __node, __ns: handled by the node itself
    if (resolve_topic_name(r.from, node_namespace, node_name) == resolved)
      return resolve_topic_name(r.to, node_namespace, node_name);
  }
  return resolved;
}

std::string to_dds_topic(const std::string& ros_topic) { return "rt" + ros_topic; }

std::string from_dds_topic(const std::string& dds_topic) {
  for (const char* p : {"rt/", "rq/", "rr/"})
    if (dds_topic.rfind(p, 0) == 0) return dds_topic.substr(2);
  return dds_topic;
}

std::string ros_type_from_dds(const std::string& dds_type) {
  const std::string marker = "::msg::dds_::";
  const size_t at = dds_type.find(marker);
  if (at == std::string::npos || dds_type.back() != '_') return dds_type;
  const std::string type = dds_type.substr(at + marker.size());
  return dds_type.substr(0, at) + "/msg/" + type.substr(0, type.size() - 1);
}

std::string dds_type_from_ros(const std::string& ros_type) {
  if (ros_type.find("::") != std::string::npos) return ros_type;
  const size_t first = ros_type.find('/');
  if (first == std::string::npos) return ros_type;
  const std::string pkg = ros_type.substr(0, first);
  const size_t last = ros_type.rfind('/');
  return pkg + "::msg::dds_::" + ros_type.substr(last + 1) + "_";
}

}  // namespace unav
