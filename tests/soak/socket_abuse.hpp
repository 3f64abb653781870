// Hostile and careless clients of the daemon's control socket, run on their own threads while
// the soak test drives the loop: garbage lines, lines cut off by a disconnect, a line over the
// server's limit, floods of requests read back and floods never read, connection churn, and
// more connections than max_clients. Each behaviour checks what the server must answer; a wrong
// answer is a failure (listed), a refusal for too many clients while another behaviour holds
// every slot is counted, not a failure.
#pragma once

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace selfsense::soak {

struct AbuseCounts {
  std::uint64_t garbage_lines{0};      // answered with "ok": false, as they must be
  std::uint64_t cut_lines{0};          // connections closed in the middle of a line
  std::uint64_t oversize_lines{0};     // answered with the error and closed
  std::uint64_t flood_replies{0};      // status replies to pipelined floods, read back in order
  std::uint64_t unread_floods{0};      // floods sent and never read
  std::uint64_t churn_connections{0};  // connect and close at once
  std::uint64_t max_client_rounds{0};  // every slot taken, the next one refused, then freed
  std::uint64_t refused_busy{0};       // refusals met while another behaviour held the slots
  std::vector<std::string> failures{};
};

class SocketAbuse final {
 public:
  // `threads` threads, each a fixed-seed sequence of behaviours, until stop().
  SocketAbuse(std::filesystem::path socket, std::size_t max_clients, int threads,
              std::uint32_t seed);
  SocketAbuse(const SocketAbuse&) = delete;
  SocketAbuse& operator=(const SocketAbuse&) = delete;
  SocketAbuse(SocketAbuse&&) = delete;
  SocketAbuse& operator=(SocketAbuse&&) = delete;
  ~SocketAbuse();

  void stop();
  [[nodiscard]] AbuseCounts counts() const;

 private:
  void run(std::uint32_t seed);

  std::filesystem::path socket_;
  std::size_t max_clients_;
  std::atomic<bool> stop_{false};
  std::mutex slots_mutex_{};  // one max_clients round at a time
  mutable std::mutex mutex_{};
  AbuseCounts counts_{};
  std::vector<std::thread> threads_{};
};

}  // namespace selfsense::soak
