// What a viewer client sends the server, parsed without the network so that it can be
// tested and fuzzed alone (fuzz/fuzz_viewer_messages.cpp): its WebSocket text messages and
// the request target of its HTTP requests and WebSocket upgrade. Built with
// viewer_server.cpp as C++17 (see viewer_server.h).
#pragma once

#include <string>

#include "viewer_server.h"

namespace dynahand::viewer {

// A client's text message: a well-formed command, or why it is refused and whether that
// client is closed for it (malformed JSON) or only answered (an unknown type or action).
struct ClientMessage {
  bool ok = false;
  ClientCommand command = ClientCommand::Pause;  // when ok
  std::string refusal;                           // when not ok
  bool close = false;                            // when not ok
};
ClientMessage parseClientMessage(const std::string& payload);

// The value of "token" in a request target's query ("/?token=..."); empty when absent.
std::string queryToken(const std::string& resource);

// Only plain relative names below the web root: letters, digits, '-', '_', '.', '/' and
// no "..", so a request can never leave the folder.
bool safeResource(const std::string& path);

}  // namespace dynahand::viewer
