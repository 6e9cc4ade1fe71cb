#include "viewer_client_input.h"

#include <nlohmann/json.hpp>

#include <string_view>

namespace dynahand::viewer {

ClientMessage parseClientMessage(const std::string& payload) {
  ClientMessage m;
  const nlohmann::json j = nlohmann::json::parse(payload, nullptr, false);
  if (j.is_discarded() || !j.is_object()) {
    m.refusal = "malformed message: expected a JSON object";
    m.close = true;
    return m;
  }
  const auto type = j.find("type");
  const auto action = j.find("action");
  if (type == j.end() || *type != "control" || action == j.end() || !action->is_string()) {
    m.refusal = "unknown message: expected {\"type\":\"control\",\"action\":...}";
    return m;
  }
  if (*action == "pause") {
    m.command = ClientCommand::Pause;
  } else if (*action == "resume") {
    m.command = ClientCommand::Resume;
  } else if (*action == "step") {
    m.command = ClientCommand::Step;
  } else {
    m.refusal = "unknown action: expected pause, resume or step";
    return m;
  }
  m.ok = true;
  return m;
}

std::string queryToken(const std::string& resource) {
  const std::size_t query = resource.find('?');
  if (query == std::string::npos) return {};
  const std::string_view all(resource);
  for (std::size_t begin = query + 1; begin <= all.size();) {
    std::size_t end = all.find('&', begin);
    if (end == std::string_view::npos) end = all.size();
    const std::string_view item = all.substr(begin, end - begin);
    if (item.substr(0, 6) == "token=") return std::string(item.substr(6));
    begin = end + 1;
  }
  return {};
}

bool safeResource(const std::string& path) {
  if (path.empty() || path.size() > 200 || path.find("..") != std::string::npos) return false;
  for (const char c : path) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '-' || c == '_' || c == '.' || c == '/';
    if (!ok) return false;
  }
  return path.front() != '/';
}

}  // namespace dynahand::viewer
