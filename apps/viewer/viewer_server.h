// The viewer's network side: one port serving the viewer page over HTTP and a WebSocket
// stream of JSON messages (docs/formats/viewer-stream.md). Runs its own I/O thread; the
// producer (tracking or the playground) calls publish() and never waits for a client:
// only the newest frame is kept, and a client whose send queue is over its limit skips
// frames until it has caught up. Client messages are bounded in size and parsed here;
// well-formed commands are queued for the producer, anything else is refused and only
// that client is answered (or closed).
//
// Only the page's own origin or a holder of this run's token may open the WebSocket: a
// browser's Origin must be http://127.0.0.1:PORT, http://localhost:PORT or
// http://HOST:PORT (HOST = ServerOptions::host), otherwise the upgrade request must carry
// the token as a query parameter ("/?token=..."); so must a client that sends no Origin.
// Anything else is answered 403 and logged on stderr (one line).
//
// websocketpp 0.8 does not compile as C++20, so viewer_server.cpp is built as C++17 and
// this header uses nothing newer (no dynahand headers).
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace dynahand::viewer {

struct ServerOptions {
  std::string host = "127.0.0.1";  // bind address; 127.0.0.1 keeps the stream local
  int port = 8080;                 // 0 = any free port (see ViewerServer::port())
  // Folder with index.html and viewer.js; empty or missing = the page is unavailable
  // (GET / explains why) while the WebSocket stream still works.
  std::filesystem::path webRoot;
  std::size_t maxClientMessageBytes = 4096;  // larger client messages close that client (1009)
  // A client with more than this many bytes waiting to be sent skips frames.
  std::size_t maxQueuedBytesPerClient = std::size_t{2} << 20;
};

// A well-formed command from a client: {"type":"control","action":"pause"|"resume"|"step"}.
enum class ClientCommand { Pause, Resume, Step };

struct ServerStats {
  int clients = 0;                       // connected WebSocket clients now
  std::uint64_t framesPublished = 0;     // publish() calls
  std::uint64_t framesSent = 0;          // frame messages queued to a client
  std::uint64_t framesDropped = 0;       // frames a client skipped because it was behind
  std::uint64_t messagesRejected = 0;    // malformed, unknown or oversized client messages
  std::uint64_t connectionsRefused = 0;  // WebSocket upgrades refused (origin, token)
};

class ViewerServer {
 public:
  // Binds and starts the I/O thread. nullptr with *error set when it cannot (address in
  // use, bad host).
  static std::unique_ptr<ViewerServer> start(const ServerOptions& options, std::string* error);
  ~ViewerServer();  // closes every connection and joins the I/O thread
  ViewerServer(const ViewerServer&) = delete;
  ViewerServer& operator=(const ViewerServer&) = delete;

  int port() const;            // the bound port
  bool pageAvailable() const;  // webRoot holds index.html
  // This run's token: 128 bits from std::random_device as 32 hex digits, new at every
  // start(). Clients that are not the page send it as "/?token=..." (see above).
  const std::string& token() const;
  // Messages every client gets first, in order, when it connects (e.g. "hello" with the
  // model's body shapes, a "scene"). Replaces the previous set; clients connected now
  // get the new set at once.
  void setWelcome(std::vector<std::string> messages);
  // The newest frame message. Never blocks on clients; cheap when nobody is connected.
  void publish(std::string message);
  // Whether anybody would receive a publish() now (lets producers skip building frames).
  bool hasClients() const;
  // Commands received since the last call, oldest first.
  std::vector<ClientCommand> takeCommands();
  ServerStats stats() const;

 private:
  struct Impl;
  explicit ViewerServer(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace dynahand::viewer
