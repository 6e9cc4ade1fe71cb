#include "viewer_server.h"

#include "viewer_client_input.h"

#define ASIO_STANDALONE
#include <nlohmann/json.hpp>
#include <websocketpp/config/asio_no_tls.hpp>
#include <websocketpp/server.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <map>
#include <mutex>
#include <random>
#include <set>
#include <sstream>
#include <thread>
#include <utility>

namespace dynahand::viewer {
namespace {

using WsServer = websocketpp::server<websocketpp::config::asio>;
using Handle = websocketpp::connection_hdl;
using Message = std::shared_ptr<const std::string>;

const char* contentType(const std::filesystem::path& file) {
  const std::string ext = file.extension().string();
  if (ext == ".html") return "text/html; charset=utf-8";
  if (ext == ".js") return "text/javascript; charset=utf-8";
  if (ext == ".css") return "text/css; charset=utf-8";
  if (ext == ".json") return "application/json";
  if (ext == ".png") return "image/png";
  if (ext == ".svg") return "image/svg+xml";
  return "application/octet-stream";
}

const char* kPageUnavailable =
    "<!doctype html><title>dynahand viewer</title><h1>Viewer page unavailable</h1>"
    "<p>This build has no viewer page: web/node_modules was missing when it was built. Run "
    "<code>scripts/install-deps.sh</code> (it runs <code>npm ci</code> in web/) and rebuild. "
    "The WebSocket stream on this port works without it (docs/formats/viewer-stream.md).</p>";

// 128 bits from the system's random source as 32 lowercase hex digits.
std::string randomToken() {
  static const char* const kHex = "0123456789abcdef";
  std::random_device device;
  std::string token;
  for (int word = 0; word < 4; ++word) {
    const std::uint32_t bits = static_cast<std::uint32_t>(device());
    for (int shift = 28; shift >= 0; shift -= 4) token += kHex[(bits >> shift) & 0xFu];
  }
  return token;
}

// Compares every character whatever the first difference, so the time taken does not tell
// how much of a guessed token was right.
bool sameSecret(const std::string& a, const std::string& b) {
  if (a.size() != b.size()) return false;
  unsigned diff = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    diff |=
        static_cast<unsigned>(static_cast<unsigned char>(a[i]) ^ static_cast<unsigned char>(b[i]));
  }
  return diff == 0;
}

std::string lowercase(std::string text) {
  for (char& c : text) {
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  }
  return text;
}

// A header value fit for a one-line log message: printable ASCII, at most 100 characters.
std::string printable(const std::string& text) {
  std::string out;
  for (const char c : text.substr(0, 100)) out += (c >= ' ' && c <= '~') ? c : '?';
  return text.size() > 100 ? out + "..." : out;
}

// The origins a browser sends for a page served by this server: http://HOST:PORT for
// 127.0.0.1, localhost and the bind address (as given and in canonical form; IPv6 in
// brackets). Browsers leave out port 80.
std::vector<std::string> pageOrigins(const std::vector<std::string>& hosts, int port) {
  const std::string suffix = port == 80 ? "" : ":" + std::to_string(port);
  std::vector<std::string> origins;
  for (const std::string& host : hosts) {
    const bool v6 = host.find(':') != std::string::npos;
    origins.push_back("http://" + lowercase(v6 ? "[" + host + "]" : host) + suffix);
  }
  return origins;
}

}  // namespace

struct ViewerServer::Impl {
  ServerOptions options;
  WsServer server;
  std::thread ioThread;
  int boundPort = 0;
  bool page = false;
  std::string token;                     // set before the I/O thread starts, then read-only
  std::vector<std::string> pageOrigins;  // likewise

  // Touched only on the I/O thread.
  std::set<Handle, std::owner_less<Handle>> clients;

  mutable std::mutex mutex;  // guards everything below
  std::vector<Message> welcome;
  Message latest;
  bool flushPosted = false;
  std::vector<ClientCommand> commands;
  ServerStats stats;
  std::atomic<int> clientCount{0};

  void sendTo(Handle h, const std::string& text) {
    websocketpp::lib::error_code ec;
    server.send(h, text, websocketpp::frame::opcode::text, ec);
  }

  void reject(Handle h, const std::string& why, bool close) {
    {
      std::lock_guard<std::mutex> lock(mutex);
      ++stats.messagesRejected;
    }
    sendTo(h, nlohmann::json{{"type", "error"}, {"version", 1}, {"message", why}}.dump());
    if (close) {
      websocketpp::lib::error_code ec;
      server.close(h, websocketpp::close::status::policy_violation, why.substr(0, 100), ec);
    }
  }

  void onMessage(Handle h, const WsServer::message_ptr& msg) {
    if (msg->get_opcode() != websocketpp::frame::opcode::text) {
      reject(h, "only text (JSON) messages are accepted", true);
      return;
    }
    const ClientMessage m = parseClientMessage(msg->get_payload());
    if (!m.ok) {
      reject(h, m.refusal, m.close);
      return;
    }
    std::lock_guard<std::mutex> lock(mutex);
    commands.push_back(m.command);
  }

  // Before a WebSocket upgrade is answered: the page's own origin or this run's token, else
  // 403 and one line on stderr.
  bool onValidate(Handle h) {
    auto con = server.get_con_from_hdl(h);
    const std::string& origin = con->get_request_header("Origin");
    if (!origin.empty() &&
        std::find(pageOrigins.begin(), pageOrigins.end(), lowercase(origin)) != pageOrigins.end()) {
      return true;
    }
    const std::string given = queryToken(con->get_resource());
    if (!given.empty() && sameSecret(given, token)) return true;
    const std::string why =
        (origin.empty() ? std::string("no Origin header")
                        : "origin " + printable(origin) + " is not the page's") +
        (given.empty() ? ", no token" : ", wrong token");
    {
      std::lock_guard<std::mutex> lock(mutex);
      ++stats.connectionsRefused;
    }
    std::fprintf(stderr, "viewer: refused a WebSocket connection from %s: %s\n",
                 printable(con->get_remote_endpoint()).c_str(), why.c_str());
    con->set_status(websocketpp::http::status_code::forbidden);
    con->append_header("Content-Type", "text/plain");
    con->set_body("WebSocket refused: " + why + ". Add the ?token=... dynahand printed.\n");
    return false;
  }

  void onOpen(Handle h) {
    clients.insert(h);
    clientCount = static_cast<int>(clients.size());
    std::vector<Message> hello;
    {
      std::lock_guard<std::mutex> lock(mutex);
      hello = welcome;
      stats.clients = clientCount;
    }
    for (const Message& m : hello) sendTo(h, *m);
  }

  void onClose(Handle h) {
    auto con = server.get_con_from_hdl(h);
    const bool tooBig = con->get_local_close_code() == websocketpp::close::status::message_too_big;
    clients.erase(h);
    clientCount = static_cast<int>(clients.size());
    std::lock_guard<std::mutex> lock(mutex);
    stats.clients = clientCount;
    if (tooBig) ++stats.messagesRejected;
  }

  void onHttp(Handle h) {
    auto con = server.get_con_from_hdl(h);
    std::string resource = con->get_resource();
    resource = resource.substr(0, resource.find('?'));
    if (resource == "/") resource = "/index.html";
    const std::string relative = resource.substr(1);
    if (!page) {
      con->set_status(websocketpp::http::status_code::service_unavailable);
      con->append_header("Content-Type", "text/html; charset=utf-8");
      con->set_body(kPageUnavailable);
      return;
    }
    std::ifstream in;
    if (safeResource(relative)) in.open(options.webRoot / relative, std::ios::binary);
    if (!in.is_open()) {  // a stream never opened has no fail bit
      con->set_status(websocketpp::http::status_code::not_found);
      con->append_header("Content-Type", "text/plain");
      con->set_body("not found\n");
      return;
    }
    std::ostringstream body;
    body << in.rdbuf();
    con->set_status(websocketpp::http::status_code::ok);
    con->append_header("Content-Type", contentType(relative));
    con->append_header("Cache-Control", "no-cache");
    con->set_body(body.str());
  }

  // On the I/O thread: sends the newest frame to every client that is keeping up.
  void flush() {
    Message frame;
    {
      std::lock_guard<std::mutex> lock(mutex);
      frame = std::move(latest);
      latest.reset();
      flushPosted = false;
    }
    if (!frame) return;
    std::uint64_t sent = 0, dropped = 0;
    for (const Handle& h : clients) {
      websocketpp::lib::error_code ec;
      auto con = server.get_con_from_hdl(h, ec);
      if (ec || con->get_state() != websocketpp::session::state::open) continue;
      if (con->get_buffered_amount() > options.maxQueuedBytesPerClient) {
        ++dropped;
        continue;
      }
      con->send(*frame, websocketpp::frame::opcode::text);
      ++sent;
    }
    std::lock_guard<std::mutex> lock(mutex);
    stats.framesSent += sent;
    stats.framesDropped += dropped;
  }

  void broadcastWelcome() {
    std::vector<Message> hello;
    {
      std::lock_guard<std::mutex> lock(mutex);
      hello = welcome;
    }
    for (const Handle& h : clients) {
      for (const Message& m : hello) sendTo(h, *m);
    }
  }
};

ViewerServer::ViewerServer(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

std::unique_ptr<ViewerServer> ViewerServer::start(const ServerOptions& options,
                                                  std::string* error) {
  auto impl = std::make_unique<Impl>();
  Impl* p = impl.get();
  p->options = options;
  p->page = !options.webRoot.empty() && std::filesystem::exists(options.webRoot / "index.html");
  try {
    p->token = randomToken();
  } catch (const std::exception& e) {  // std::random_device has no source
    if (error) *error = std::string("no random source for the viewer's token: ") + e.what();
    return nullptr;
  }
  WsServer& s = p->server;
  s.clear_access_channels(websocketpp::log::alevel::all);
  s.clear_error_channels(websocketpp::log::elevel::all);
  websocketpp::lib::error_code ec;
  s.init_asio(ec);
  if (ec) {
    if (error) *error = "cannot start the network loop: " + ec.message();
    return nullptr;
  }
  s.set_reuse_addr(true);
  s.set_max_message_size(options.maxClientMessageBytes);
  s.set_open_handler([p](Handle h) { p->onOpen(h); });
  s.set_close_handler([p](Handle h) { p->onClose(h); });
  s.set_message_handler([p](Handle h, WsServer::message_ptr m) { p->onMessage(h, m); });
  s.set_http_handler([p](Handle h) { p->onHttp(h); });
  s.set_validate_handler([p](Handle h) { return p->onValidate(h); });
  // A small kernel send buffer keeps a slow client's backlog in our queue, where it is
  // counted and frames are skipped, instead of megabytes of stale frames in the kernel.
  s.set_socket_init_handler([p](Handle, asio::ip::tcp::socket& socket) {
    asio::error_code ignored;
    socket.set_option(asio::ip::tcp::no_delay(true), ignored);
    socket.set_option(asio::socket_base::send_buffer_size(static_cast<int>(std::min<std::size_t>(
                          p->options.maxQueuedBytesPerClient, std::size_t{256} << 10))),
                      ignored);
  });

  asio::error_code aec;
  const auto address = asio::ip::make_address(options.host, aec);
  if (aec) {
    if (error) *error = "--host: not an IP address: " + options.host;
    return nullptr;
  }
  s.listen(asio::ip::tcp::endpoint(address, static_cast<unsigned short>(options.port)), ec);
  if (!ec) s.start_accept(ec);
  if (ec) {
    if (error) {
      *error = "cannot listen on " + options.host + ":" + std::to_string(options.port) + ": " +
               ec.message();
    }
    return nullptr;
  }
  p->boundPort = s.get_local_endpoint(ec).port();
  p->pageOrigins =
      pageOrigins({"127.0.0.1", "localhost", options.host, address.to_string()}, p->boundPort);
  p->ioThread = std::thread([p] { p->server.run(); });
  return std::unique_ptr<ViewerServer>(new ViewerServer(std::move(impl)));
}

ViewerServer::~ViewerServer() {
  Impl* p = impl_.get();
  asio::post(p->server.get_io_service(), [p] {
    websocketpp::lib::error_code ec;
    p->server.stop_listening(ec);
    for (const Handle& h : p->clients) {
      p->server.close(h, websocketpp::close::status::going_away, "server stopping", ec);
    }
  });
  // Give clients a moment to answer the close handshake, then stop regardless.
  for (int i = 0; i < 50 && p->clientCount > 0; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  p->server.stop();
  if (p->ioThread.joinable()) p->ioThread.join();
}

int ViewerServer::port() const {
  return impl_->boundPort;
}
const std::string& ViewerServer::token() const {
  return impl_->token;
}
bool ViewerServer::pageAvailable() const {
  return impl_->page;
}
bool ViewerServer::hasClients() const {
  return impl_->clientCount > 0;
}

void ViewerServer::setWelcome(std::vector<std::string> messages) {
  Impl* p = impl_.get();
  {
    std::lock_guard<std::mutex> lock(p->mutex);
    p->welcome.clear();
    for (std::string& m : messages) {
      p->welcome.push_back(std::make_shared<const std::string>(std::move(m)));
    }
  }
  asio::post(p->server.get_io_service(), [p] { p->broadcastWelcome(); });
}

void ViewerServer::publish(std::string message) {
  Impl* p = impl_.get();
  std::lock_guard<std::mutex> lock(p->mutex);
  ++p->stats.framesPublished;
  if (p->clientCount == 0) return;
  p->latest = std::make_shared<const std::string>(std::move(message));
  if (!p->flushPosted) {
    p->flushPosted = true;
    asio::post(p->server.get_io_service(), [p] { p->flush(); });
  }
}

std::vector<ClientCommand> ViewerServer::takeCommands() {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return std::exchange(impl_->commands, {});
}

ServerStats ViewerServer::stats() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->stats;
}

}  // namespace dynahand::viewer
