#include "soak.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <random>
#include <thread>

#include <fmt/format.h>

#include "dynahand/metrics.h"
#include "dynahand/sequence.h"
#include "dynahand/synth.h"
#include "dynahand/tracker.h"
#include "serve_session.h"
#include "viewer_server.h"

namespace dynahand::cli::soak {
namespace {

using Clock = std::chrono::steady_clock;

// VmRSS and VmHWM of /proc/self/status, MB (0 where unreadable).
struct Memory {
  double rssMb = 0.0, hwmMb = 0.0;
};
Memory readMemory() {
  Memory m;
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line)) {
    const bool rss = line.rfind("VmRSS:", 0) == 0, hwm = line.rfind("VmHWM:", 0) == 0;
    if (!rss && !hwm) continue;
    const double kb = std::strtod(line.c_str() + 6, nullptr);
    (rss ? m.rssMb : m.hwmMb) = kb / 1024.0;
  }
  return m;
}

double soakThreadCpuMs() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return 1e3 * static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_nsec);
}

std::string minutesClock(double seconds) {
  const int s = static_cast<int>(seconds + 0.5);
  return fmt::format("{}:{:02d}", s / 60, s % 60);
}

// Seconds, whole ones when there are enough of them.
std::string secondsText(double s) {
  return s >= 10.0 ? fmt::format("{:.0f}", s) : fmt::format("{:.1f}", s);
}
std::string spanText(double from, double to) {
  return secondsText(from) + "-" + secondsText(to);
}

// One frame's times, kept only for the two windows.
struct FrameSample {
  float atS = 0.0f;  // end of the frame, s since the start
  float wallMs = 0.0f, cpuMs = 0.0f;
};

// The time line of a run (see soak.h): warm-up, the two windows, resident memory once a
// second, progress lines every 10 %. The buffers for the windows are allocated and touched
// at the end of the warm-up, before the memory is read, so that the measurement itself
// does not grow afterwards.
class Recorder {
 public:
  Recorder(const SoakOptions& o, SoakReport& report) : o_(o), r_(report) {
    r_.plannedS = o.seconds;
    r_.warmUpS = std::min(60.0, o.seconds / 10.0);
    windowS_ = std::min(300.0, std::max(r_.warmUpS, o.seconds / 10.0));
    r_.first.fromS = r_.warmUpS;
    r_.first.toS = r_.warmUpS + windowS_;
    r_.last.fromS = o.seconds - windowS_;
    r_.last.toS = o.seconds;
  }

  void begin() {
    const Memory m = readMemory();
    r_.rssStartMb = r_.rssPeakMb = m.rssMb;
    r_.rssAtTenths.reserve(11);
    r_.rssAtTenths.push_back(m.rssMb);
    start_ = Clock::now();
    nextSampleS_ = 1.0;
    std::printf("soak %s: %s for %s (warm-up %s s, windows of %s s)\n", r_.mode.c_str(),
                r_.input.c_str(), minutesClock(o_.seconds).c_str(), secondsText(r_.warmUpS).c_str(),
                secondsText(windowS_).c_str());
    std::fflush(stdout);
  }

  // False once the time is up or the run was asked to stop.
  bool running() {
    nowS_ = std::chrono::duration<double>(Clock::now() - start_).count();
    if (o_.stop && o_.stop()) {
      r_.interrupted = true;
      return false;
    }
    return nowS_ < o_.seconds;
  }

  void add(double wallMs, double cpuMs, bool tracked) {
    const double t = std::chrono::duration<double>(Clock::now() - start_).count();
    ++r_.frames;
    r_.trackedFrames += tracked ? 1 : 0;
    if (!warm_ && t >= r_.warmUpS) endWarmUp(t);
    const FrameSample s{static_cast<float>(t), static_cast<float>(wallMs),
                        static_cast<float>(cpuMs)};
    if (warm_) {
      if (t < r_.first.toS && firstCount_ < first_.size()) first_[firstCount_++] = s;
      ring_[ringNext_] = s;
      ringNext_ = (ringNext_ + 1) % ring_.size();
      ringCount_ = std::min(ringCount_ + 1, ring_.size());
    }
    if (t >= nextSampleS_) {
      nextSampleS_ = std::floor(t) + 1.0;
      r_.rssPeakMb = std::max(r_.rssPeakMb, readMemory().rssMb);
    }
    while (nextTenth_ <= 9 && t >= o_.seconds * nextTenth_ / 10.0) {
      const Memory m = readMemory();
      r_.rssAtTenths.push_back(m.rssMb);
      std::printf("soak %s %s / %s  frames %lld (%.0f/s)  resident %.1f MB\n", r_.mode.c_str(),
                  minutesClock(t).c_str(), minutesClock(o_.seconds).c_str(), r_.frames,
                  static_cast<double>(r_.frames) / t, m.rssMb);
      std::fflush(stdout);
      ++nextTenth_;
    }
  }

  void finish() {
    r_.elapsedS = std::chrono::duration<double>(Clock::now() - start_).count();
    const Memory m = readMemory();
    r_.rssEndMb = m.rssMb;
    r_.rssHwmMb = m.hwmMb;
    r_.rssPeakMb = std::max(r_.rssPeakMb, m.rssMb);
    r_.rssAtTenths.push_back(m.rssMb);
    if (!warm_) return;  // stopped inside the warm-up: no windows
    summarize(r_.first, first_.data(), firstCount_);
    r_.first.toS = std::min(r_.first.toS, r_.elapsedS);
    // The ring's frames inside the last window's span (all of them when the ring holds less).
    std::vector<FrameSample> last;
    last.reserve(ringCount_);
    const double from = r_.elapsedS - windowS_;
    for (std::size_t i = 0; i < ringCount_; ++i) {
      const FrameSample& s = ring_[(ringNext_ + ring_.size() - ringCount_ + i) % ring_.size()];
      if (static_cast<double>(s.atS) >= from) last.push_back(s);
    }
    summarize(r_.last, last.data(), last.size());
    r_.last.fromS = last.empty() ? from : static_cast<double>(last.front().atS);
    r_.last.toS = r_.elapsedS;
  }

 private:
  void endWarmUp(double t) {
    warm_ = true;
    // Room for twice the warm-up's frame rate over a window (at least 2000 frames); a later,
    // faster pace fills the first window's buffer early and shortens the ring's span.
    const double rate = static_cast<double>(r_.frames) / std::max(t, 1e-3);
    const auto capacity = static_cast<std::size_t>(std::max(2000.0, 2.0 * rate * windowS_));
    first_.assign(capacity, FrameSample{});  // assign writes every element: pages touched
    ring_.assign(capacity, FrameSample{});
    r_.rssWarmMb = readMemory().rssMb;
    r_.rssPeakMb = std::max(r_.rssPeakMb, r_.rssWarmMb);
  }

  static void summarize(SoakWindow& w, const FrameSample* s, std::size_t n) {
    w.frames = static_cast<int>(n);
    if (n == 0) return;
    std::vector<double> wall(n), cpu(n);
    for (std::size_t i = 0; i < n; ++i) {
      wall[i] = static_cast<double>(s[i].wallMs);
      cpu[i] = static_cast<double>(s[i].cpuMs);
    }
    w.p50Ms = eval::percentile(wall, 0.5);
    w.p99Ms = eval::percentile(wall, 0.99);
    w.cpuP50Ms = eval::percentile(cpu, 0.5);
    w.cpuP99Ms = eval::percentile(std::move(cpu), 0.99);
  }

  const SoakOptions& o_;
  SoakReport& r_;
  double windowS_ = 0.0;
  Clock::time_point start_;
  double nowS_ = 0.0, nextSampleS_ = 1.0;
  int nextTenth_ = 1;
  bool warm_ = false;
  std::vector<FrameSample> first_, ring_;
  std::size_t firstCount_ = 0, ringNext_ = 0, ringCount_ = 0;
};

// ---- track ----

// Frames as `dynahand track` gets them: synthetic clips rendered in turn, or a recording
// read frame by frame; both looped.
class TrackInput {
 public:
  static Result<TrackInput> open(const SoakOptions& o) {
    TrackInput in;
    if (o.input.rfind("synth:", 0) == 0) {
      std::string rest = o.input.substr(6);
      while (!rest.empty()) {
        const auto comma = rest.find(',');
        synth::SynthOptions so;
        so.clip = rest.substr(0, comma);
        so.profile = o.profile;
        so.frameCount = o.clipFrames;
        auto seq = synth::SyntheticSequence::create(so);
        if (!seq) return Error{"--soak-input " + o.input + ": " + seq.message()};
        if (!in.clips.empty() && seq->handCount() != in.clips.front().handCount())
          return Error{"--soak-input " + o.input + ": clips with one hand and two mixed"};
        in.clips.push_back(std::move(*seq));
        rest = comma == std::string::npos ? "" : rest.substr(comma + 1);
      }
      if (in.clips.empty()) return Error{"--soak-input synth: names no clip"};
      in.intrinsics = in.clips.front().intrinsics();
      in.minRangeM = in.clips.front().profile().minRange;
      in.hands = in.clips.front().handCount();
      return in;
    }
    if (!std::filesystem::exists(o.input)) return Error{"--soak-input: not found: " + o.input};
    auto reader = SequenceReader::open(o.input);
    if (!reader) return Error{"--soak-input: " + reader.message()};
    if (reader->frameCount() <= 0) return Error{"--soak-input " + o.input + ": holds no frames"};
    in.reader.emplace(std::move(*reader));
    in.intrinsics = in.reader->info().intrinsics;
    in.minRangeM = in.reader->info().minRangeM;
    return in;
  }

  Result<const DepthFrame*> next() {
    if (reader) {
      auto f = reader->frame(index_);
      if (!f) return Error{f.message()};
      frame_ = std::move(*f);
      if (++index_ >= reader->frameCount()) index_ = 0;
      return &frame_;
    }
    const DepthFrame* d = &clips[clip_].frame(index_).depth;
    if (++index_ >= clips[clip_].frameCount()) {
      index_ = 0;
      clip_ = (clip_ + 1) % clips.size();
    }
    return d;
  }

  std::vector<synth::SyntheticSequence> clips;
  std::optional<SequenceReader> reader;
  Intrinsics intrinsics;
  float minRangeM = 0.0f;  // the camera's near range (m); 0 = not known
  int hands = 1;

 private:
  std::size_t clip_ = 0;
  int index_ = 0;
  DepthFrame frame_;
};

Result<SoakReport> runTrackSoak(const SoakOptions& o) {
  auto in = TrackInput::open(o);
  if (!in) return in.error();
  // As `dynahand track INPUT` with its defaults: the built-in hand at 0.19 x 0.085 m,
  // automatic acquisition, one thread, the learned detector unless --no-detector.
  track::TrackerSettings settings;
  settings.hands = in->hands;
  settings.threads = 1;
  settings.detector.enabled = o.detector;
  if (in->minRangeM > 0.0f) settings.cloud.segmentation.sensorMinRangeM = in->minRangeM;
  auto tracker = track::Tracker::create(model::makeDefaultHand(), in->intrinsics, settings);
  if (!tracker) return tracker.error();

  SoakReport report;
  report.mode = "track";
  report.input = o.input.rfind("synth:", 0) == 0
                     ? fmt::format("{} ({}, {} frames per clip)", o.input, o.profile, o.clipFrames)
                     : o.input;
  report.timed = o.input.rfind("synth:", 0) == 0
                     ? "Tracker::track (synthesis not included)"
                     : "Tracker::track (reading the frame not included)";
  Recorder recorder(o, report);
  recorder.begin();
  while (recorder.running()) {
    auto depth = in->next();
    if (!depth) return depth.error();
    const double cpu0 = soakThreadCpuMs();
    const auto t0 = Clock::now();
    const track::TrackResult& r = (*tracker)->track(**depth);
    const double wall = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    const double cpu = soakThreadCpuMs() - cpu0;
    recorder.add(wall, cpu, !r.hands.empty() && r.hands.front().tracked);
  }
  recorder.finish();
  return report;
}

// ---- serve ----

// A viewer over loopback that reads every message (a browser tab that keeps up): the
// WebSocket handshake with the run's token, then the server's frames parsed just enough to
// count whole messages and the "frame" messages among them. Fixed memory: payloads are read
// and dropped.
class StreamClient {
 public:
  // Connects and completes the handshake; nullptr with *error set when it cannot.
  static std::unique_ptr<StreamClient> connect(int port, const std::string& token,
                                               std::string* error) {
    std::unique_ptr<StreamClient> c(new StreamClient);
    c->fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_port = htons(static_cast<std::uint16_t>(port));
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (c->fd_ < 0 ||
        ::connect(c->fd_, reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0) {
      *error = fmt::format("cannot connect to 127.0.0.1:{}: {}", port, std::strerror(errno));
      return nullptr;
    }
    // Not the page (no Origin), so the token goes in the query.
    const std::string request = fmt::format(
        "GET /?token={} HTTP/1.1\r\nHost: 127.0.0.1:{}\r\nUpgrade: websocket\r\n"
        "Connection: Upgrade\r\nSec-WebSocket-Key: {}\r\nSec-WebSocket-Version: 13\r\n\r\n",
        token, port, randomKey());
    if (::send(c->fd_, request.data(), request.size(), MSG_NOSIGNAL) !=
        static_cast<ssize_t>(request.size())) {
      *error = "cannot send the WebSocket handshake";
      return nullptr;
    }
    // The answer's header, then whatever frames came with it.
    std::string answer;
    char buffer[4096];
    std::size_t end = std::string::npos;
    const auto deadline = Clock::now() + std::chrono::seconds(10);
    while (end == std::string::npos && answer.size() < 65536 && Clock::now() < deadline) {
      pollfd p{c->fd_, POLLIN, 0};
      if (::poll(&p, 1, 100) <= 0) continue;
      const ssize_t n = ::recv(c->fd_, buffer, sizeof buffer, 0);
      if (n <= 0) break;
      answer.append(buffer, static_cast<std::size_t>(n));
      end = answer.find("\r\n\r\n");
    }
    if (end == std::string::npos || answer.rfind("HTTP/1.1 101", 0) != 0) {
      *error = "the WebSocket handshake was not accepted: " +
               answer.substr(0, std::min(answer.find('\r'), answer.size()));
      return nullptr;
    }
    c->feed(reinterpret_cast<const unsigned char*>(answer.data()) + end + 4,
            answer.size() - end - 4);
    StreamClient* self = c.get();
    c->reader_ = std::thread([self] { self->read(); });
    return c;
  }
  ~StreamClient() {
    stop_ = true;
    if (reader_.joinable()) reader_.join();
    if (fd_ >= 0) ::close(fd_);
  }
  StreamClient(const StreamClient&) = delete;
  StreamClient& operator=(const StreamClient&) = delete;

  unsigned long long messages() const { return messages_; }
  unsigned long long frames() const { return frames_; }
  unsigned long long bytes() const { return bytes_; }
  bool closed() const { return closed_; }

 private:
  StreamClient() = default;

  // 16 random bytes in base64 (RFC 6455's Sec-WebSocket-Key).
  static std::string randomKey() {
    static constexpr char kDigits[] =
        "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::random_device random;
    std::array<unsigned char, 18> bytes{};  // 16 random, 2 zero for the last group
    for (std::size_t i = 0; i < 16; ++i) bytes[i] = static_cast<unsigned char>(random() & 0xff);
    std::string key;
    for (std::size_t i = 0; i < 18; i += 3) {
      const unsigned v = (unsigned{bytes[i]} << 16) | (unsigned{bytes[i + 1]} << 8) | bytes[i + 2];
      for (int shift = 18; shift >= 0; shift -= 6) key += kDigits[(v >> shift) & 63u];
    }
    return key.substr(0, 22) + "==";
  }

  void read() {
    std::array<unsigned char, 1 << 16> buffer{};
    while (!stop_ && !closed_) {
      pollfd p{fd_, POLLIN, 0};
      if (::poll(&p, 1, 50) <= 0) continue;
      const ssize_t n = ::recv(fd_, buffer.data(), buffer.size(), 0);
      if (n <= 0) {
        closed_ = true;
        break;
      }
      feed(buffer.data(), static_cast<std::size_t>(n));
    }
  }

  // Server frames are unmasked: 2 header bytes, 0/2/8 bytes of length, the payload.
  void feed(const unsigned char* data, std::size_t n) {
    bytes_ += n;
    std::size_t at = 0;
    while (at < n) {
      if (!inPayload_) {
        header_[headerSize_++] = data[at++];
        if (headerSize_ < 2) continue;
        const unsigned length7 = header_[1] & 0x7fu;
        const std::size_t needed = 2 +
                                   (length7 == 126   ? 2
                                    : length7 == 127 ? 8
                                                     : 0) +
                                   ((header_[1] & 0x80u) != 0 ? 4 : 0);
        if (headerSize_ < needed) continue;
        std::uint64_t length = length7;
        if (length7 >= 126) {
          length = 0;
          for (std::size_t i = 2; i < (length7 == 126 ? 4u : 10u); ++i)
            length = (length << 8) | header_[i];
        }
        fin_ = (header_[0] & 0x80u) != 0;
        opcode_ = header_[0] & 0x0fu;
        remaining_ = length;
        headerSize_ = 0;
        inPayload_ = true;
      } else {
        const std::size_t take =
            static_cast<std::size_t>(std::min<std::uint64_t>(remaining_, n - at));
        if (opcode_ < 8) {  // data: keep the message's first bytes to tell its type
          const std::size_t keep = std::min(take, prefix_.size() - prefixSize_);
          std::memcpy(prefix_.data() + prefixSize_, data + at, keep);
          prefixSize_ += keep;
        }
        at += take;
        remaining_ -= take;
      }
      if (inPayload_ && remaining_ == 0) endOfFrame();
    }
  }

  void endOfFrame() {
    inPayload_ = false;
    if (opcode_ == 8) closed_ = true;
    if (opcode_ >= 8 || !fin_) return;  // control frame, or a message continues
    ++messages_;
    static constexpr char kFrame[] = "{\"type\":\"frame\"";
    if (prefixSize_ == sizeof kFrame - 1 && std::memcmp(prefix_.data(), kFrame, prefixSize_) == 0)
      ++frames_;
    prefixSize_ = 0;
  }

  int fd_ = -1;
  std::thread reader_;
  std::atomic<bool> stop_{false}, closed_{false};
  std::atomic<unsigned long long> messages_{0}, frames_{0}, bytes_{0};
  // The parser (the reader thread's, or connect()'s before it starts).
  std::array<unsigned char, 14> header_{};
  std::size_t headerSize_ = 0;
  bool inPayload_ = false, fin_ = false;
  unsigned opcode_ = 0;
  std::uint64_t remaining_ = 0;
  std::array<char, 15> prefix_{};  // strlen("{\"type\":\"frame\"")
  std::size_t prefixSize_ = 0;
};

Result<SoakReport> runServeSoak(const SoakOptions& o) {
  if (o.input.find(',') != std::string::npos)
    return Error{"--soak-input " + o.input + ": --serve takes one input, as dynahand serve"};
  // As `dynahand serve INPUT --fast` (or without --fast with --paced) with its defaults.
  viewer::ServeOptions so;
  so.input = o.input;
  so.synthFrames = o.clipFrames;
  so.synthProfile = o.profile;
  so.settings.detector.enabled = o.detector;
  auto session = viewer::ServeSession::open(so);
  if (!session) return Error{"--soak-input: " + session.message()};
  viewer::ServerOptions serverOptions;
  serverOptions.port = 0;
  std::string error;
  auto server = viewer::ViewerServer::start(serverOptions, &error);
  if (!server) return Error{"the viewer server: " + error};
  server->setWelcome({(*session)->hello()});
  auto client = StreamClient::connect(server->port(), server->token(), &error);
  if (!client) return Error{"the stream client: " + error};
  for (int i = 0; i < 500 && !server->hasClients(); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  if (!server->hasClients()) return Error{"the stream client did not connect"};

  SoakReport report;
  report.mode = "serve";
  report.input = o.input.rfind("synth:", 0) == 0
                     ? fmt::format("{} ({}, {} frames per loop)", o.input, o.profile, o.clipFrames)
                     : o.input;
  report.input += o.paced ? ", paced at the input's rate" : ", as fast as it goes (--fast)";
  report.input += ", one WebSocket client";
  report.timed =
      o.input.rfind("synth:", 0) == 0
          ? "ServeSession::step: render the synthetic frame, track it, build the frame message "
            "(poses, candidates, clouds) and hand it to the server"
          : "ServeSession::step: read the frame, track it, build the frame message (poses, "
            "candidates, clouds) and hand it to the server";
  const auto period = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(1.0 / static_cast<double>((*session)->framesPerSecond())));
  Recorder recorder(o, report);
  recorder.begin();
  auto due = Clock::now();
  while (recorder.running()) {
    (void)server->takeCommands();  // as dynahand serve's loop (the client sends none)
    const double cpu0 = soakThreadCpuMs();
    const auto t0 = Clock::now();
    const Status s = (*session)->step(server.get());
    const double wall = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    const double cpu = soakThreadCpuMs() - cpu0;
    if (!s) return s.error();
    const track::TrackResult* r = (*session)->lastResult();
    recorder.add(wall, cpu, r != nullptr && !r->hands.empty() && r->hands.front().tracked);
    if (o.paced) {
      due += period;
      const auto now = Clock::now();
      if (due > now) {
        std::this_thread::sleep_until(due);
      } else {
        due = now;
      }
    }
  }
  recorder.finish();
  // Let the client read what is still on its way.
  const auto deadline = Clock::now() + std::chrono::seconds(10);
  while (!client->closed() && client->frames() < server->stats().framesSent &&
         Clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  const viewer::ServerStats stats = server->stats();
  report.framesPublished = stats.framesPublished;
  report.framesSent = stats.framesSent;
  report.framesDropped = stats.framesDropped;
  report.clientsAtEnd = stats.clients;
  report.messagesReceived = client->messages();
  report.framesReceived = client->frames();
  report.megabytesReceived = static_cast<double>(client->bytes()) / 1e6;
  return report;
}

std::string percentText(double fraction) {
  return std::isfinite(fraction) ? fmt::format("{:+.1f}%", 100.0 * fraction) : "n/a";
}

std::string verdictText(bool ok, bool measured) {
  return !measured ? "n/a" : ok ? "PASS" : "FAIL";
}

}  // namespace

double SoakReport::rssChange() const {
  return rssWarmMb > 0.0 ? (rssEndMb - rssWarmMb) / rssWarmMb : std::nan("");
}
double SoakReport::p99Change() const {
  return first.frames > 0 && last.frames > 0 && first.p99Ms > 0.0
             ? (last.p99Ms - first.p99Ms) / first.p99Ms
             : std::nan("");
}
bool SoakReport::measured() const {
  return first.frames > 0 && last.frames > 0 && last.fromS >= first.toS;
}
double SoakReport::cpuP99Change() const {
  return first.frames > 0 && last.frames > 0 && first.cpuP99Ms > 0.0
             ? (last.cpuP99Ms - first.cpuP99Ms) / first.cpuP99Ms
             : std::nan("");
}
bool SoakReport::rssOk() const {
  return rssChange() <= kRssTolerance;  // growth is what fails; false for NaN
}
bool SoakReport::p99Ok() const {
  return p99Change() <= kP99Tolerance;  // a slower end fails, a faster one does not
}

Result<SoakReport> runSoak(const SoakOptions& options) {
  SoakOptions o = options;
  if (o.input.empty()) o.input = o.serve ? "synth:wave" : "synth:wave,open-close,pinch";
  if (!(o.seconds > 0.0)) return Error{"the soak needs a positive time"};
  return o.serve ? runServeSoak(o) : runTrackSoak(o);
}

std::string soakText(const SoakReport& r) {
  std::string s;
  auto out = std::back_inserter(s);
  const double rate = r.elapsedS > 0.0 ? static_cast<double>(r.frames) / r.elapsedS : 0.0;
  fmt::format_to(out, "soak {}: {}\n", r.mode, r.input);
  fmt::format_to(out, "run {} of {} planned{}; frames {} ({:.1f}/s), hand tracked in {:.1f}%\n",
                 minutesClock(r.elapsedS), minutesClock(r.plannedS),
                 r.interrupted ? " (interrupted)" : "", r.frames, rate,
                 r.frames > 0
                     ? 100.0 * static_cast<double>(r.trackedFrames) / static_cast<double>(r.frames)
                     : 0.0);
  fmt::format_to(out, "frame time: {}, one thread\n", r.timed);
  if (r.mode == "serve") {
    fmt::format_to(out,
                   "stream: {} frames published, {} sent, {} dropped for a slow client; the "
                   "client received {} frames ({} messages, {:.1f} MB){}\n",
                   r.framesPublished, r.framesSent, r.framesDropped, r.framesReceived,
                   r.messagesReceived, r.megabytesReceived,
                   r.clientsAtEnd == 1 ? "" : "; the client was no longer connected at the end");
  }
  fmt::format_to(out, "{:<24}{:>16}{:>16}{:>10}   {}\n", "", "first window", "last window",
                 "change", "criterion");
  fmt::format_to(out, "{:<24}{:>16}{:>16}\n", "window (s)", spanText(r.first.fromS, r.first.toS),
                 spanText(r.last.fromS, r.last.toS));
  fmt::format_to(out, "{:<24}{:>16}{:>16}\n", "frames", r.first.frames, r.last.frames);
  const bool timed = r.measured();
  fmt::format_to(out, "{:<24}{:>16.2f}{:>16.2f}{:>10}\n", "p50 frame time (ms)", r.first.p50Ms,
                 r.last.p50Ms,
                 timed ? percentText((r.last.p50Ms - r.first.p50Ms) / r.first.p50Ms) : "n/a");
  fmt::format_to(out, "{:<24}{:>16.2f}{:>16.2f}{:>10}   at most +10%: {}\n", "p99 frame time (ms)",
                 r.first.p99Ms, r.last.p99Ms, percentText(r.p99Change()),
                 verdictText(r.p99Ok(), timed));
  fmt::format_to(out, "{:<24}{:>16}{:>16}{:>10}   (p99)\n", "p50 / p99 CPU (ms)",
                 fmt::format("{:.2f} / {:.2f}", r.first.cpuP50Ms, r.first.cpuP99Ms),
                 fmt::format("{:.2f} / {:.2f}", r.last.cpuP50Ms, r.last.cpuP99Ms),
                 percentText(r.cpuP99Change()));
  fmt::format_to(out, "{:<24}{:>16.1f}{:>16.1f}{:>10}   at most +5%: {}\n", "resident memory (MB)",
                 r.rssWarmMb, r.rssEndMb, percentText(r.rssChange()),
                 verdictText(r.rssOk(), r.rssWarmMb > 0.0));
  fmt::format_to(out,
                 "{:<24}after warm-up ({} s) and at the end; start {:.1f}, peak {:.1f}, "
                 "VmHWM {:.1f}\n",
                 "", secondsText(r.warmUpS), r.rssStartMb, r.rssPeakMb, r.rssHwmMb);
  std::string tenths;
  for (const double mb : r.rssAtTenths) tenths += fmt::format(" {:.1f}", mb);
  fmt::format_to(out, "resident memory (MB) at 0%, 10%, ..., 100% of the run:{}\n", tenths);
  fmt::format_to(out, "soak {}: {}\n", r.mode,
                 r.pass() ? "PASS"
                 : timed  ? "FAIL"
                          : "FAIL (too short to measure: the windows overlap or are empty)");
  if (timed && !r.p99Ok() && r.cpuP99Change() <= SoakReport::kP99Tolerance) {
    s += "(the p99 of the CPU time grew by at most 10 %: the wall time's change is likely the "
         "machine's load, not the program)\n";
  }
  return s;
}

std::string soakMarkdown(const SoakReport& r) {
  std::string s;
  auto out = std::back_inserter(s);
  const double rate = r.elapsedS > 0.0 ? static_cast<double>(r.frames) / r.elapsedS : 0.0;
  const bool timed = r.measured();
  fmt::format_to(out, "## Soak: {}\n\n", r.mode);
  fmt::format_to(out, "- Input: {}\n", r.input);
  fmt::format_to(
      out, "- Run: {:.1f} min{}, {} frames ({:.1f}/s), hand tracked in {:.1f}% of them\n",
      r.elapsedS / 60.0, r.interrupted ? " (interrupted)" : "", r.frames, rate,
      r.frames > 0 ? 100.0 * static_cast<double>(r.trackedFrames) / static_cast<double>(r.frames)
                   : 0.0);
  fmt::format_to(out, "- Frame time: {}, one thread\n", r.timed);
  if (r.mode == "serve") {
    fmt::format_to(out,
                   "- Stream: {} frames published, {} sent to the client and {} dropped for a "
                   "slow client; the client received {} frames ({} messages, {:.1f} MB)\n",
                   r.framesPublished, r.framesSent, r.framesDropped, r.framesReceived,
                   r.messagesReceived, r.megabytesReceived);
  }
  fmt::format_to(out,
                 "- Warm-up {} s; first window {} s ({} frames), last window {} s ({} frames)\n\n",
                 secondsText(r.warmUpS), spanText(r.first.fromS, r.first.toS), r.first.frames,
                 spanText(r.last.fromS, r.last.toS), r.last.frames);
  s += "| | after warm-up / first window | end / last window | change | criterion | result |\n"
       "| --- | ---: | ---: | ---: | --- | --- |\n";
  fmt::format_to(out, "| resident memory (MB) | {:.1f} | {:.1f} | {} | at most +5 % | {} |\n",
                 r.rssWarmMb, r.rssEndMb, percentText(r.rssChange()),
                 verdictText(r.rssOk(), r.rssWarmMb > 0.0));
  fmt::format_to(out, "| p99 frame time (ms) | {:.2f} | {:.2f} | {} | at most +10 % | {} |\n",
                 r.first.p99Ms, r.last.p99Ms, percentText(r.p99Change()),
                 verdictText(r.p99Ok(), timed));
  fmt::format_to(out, "| p50 frame time (ms) | {:.2f} | {:.2f} | {} | | |\n", r.first.p50Ms,
                 r.last.p50Ms,
                 timed ? percentText((r.last.p50Ms - r.first.p50Ms) / r.first.p50Ms) : "n/a");
  fmt::format_to(
      out, "| p50 / p99 CPU time (ms) | {:.2f} / {:.2f} | {:.2f} / {:.2f} | {} (p99) | | |\n\n",
      r.first.cpuP50Ms, r.first.cpuP99Ms, r.last.cpuP50Ms, r.last.cpuP99Ms,
      percentText(r.cpuP99Change()));
  std::string tenths;
  for (const double mb : r.rssAtTenths)
    tenths += fmt::format("{}{:.1f}", tenths.empty() ? "" : ", ", mb);
  fmt::format_to(out,
                 "Resident memory (MB) at 0 %, 10 %, ..., 100 % of the run: {}; start {:.1f}, "
                 "peak {:.1f}, VmHWM {:.1f}.\n\nResult: **{}**\n",
                 tenths, r.rssStartMb, r.rssPeakMb, r.rssHwmMb,
                 r.pass() ? "PASS"
                 : timed  ? "FAIL"
                          : "FAIL (too short to measure)");
  return s;
}

}  // namespace dynahand::cli::soak
