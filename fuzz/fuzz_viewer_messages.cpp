// libFuzzer target: what a client of `dynahand serve` / `play --serve` sends: WebSocket text
// messages (viewer::parseClientMessage) and request targets (viewer::queryToken for the
// upgrade's token, viewer::safeResource for the page's files), all from the same bytes.
// Nothing may crash or hang; a command is only accepted from a JSON object of type
// "control", a token is what follows "token=" in the query, and a resource judged safe
// cannot leave the web root.
#include <cstddef>
#include <cstdint>
#include <string>

#include <nlohmann/json.hpp>

#include "fuzz_util.h"
#include "viewer_client_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string bytes(dynahand::fuzz::text({data, size}));

  const dynahand::viewer::ClientMessage message = dynahand::viewer::parseClientMessage(bytes);
  if (message.ok) {
    const auto j = nlohmann::json::parse(bytes, nullptr, false);
    FUZZ_CHECK(!j.is_discarded() && j.is_object());
    FUZZ_CHECK(j.contains("type") && j["type"] == "control");
    FUZZ_CHECK(j.contains("action") && j["action"].is_string());
  } else {
    FUZZ_CHECK(!message.refusal.empty());
  }

  const std::string token = dynahand::viewer::queryToken(bytes);
  if (!token.empty()) {
    const std::size_t query = bytes.find('?');
    FUZZ_CHECK(query != std::string::npos);
    FUZZ_CHECK(bytes.find("token=" + token, query + 1) != std::string::npos);
  }

  if (dynahand::viewer::safeResource(bytes)) {
    FUZZ_CHECK(!bytes.empty() && bytes.size() <= 200 && bytes.front() != '/');
    FUZZ_CHECK(bytes.find("..") == std::string::npos);
    FUZZ_CHECK(bytes.find('\\') == std::string::npos && bytes.find('\0') == std::string::npos);
    FUZZ_CHECK(bytes.find('%') == std::string::npos);  // no escapes to decode into ".."
  }
  return 0;
}
