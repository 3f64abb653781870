// The CAN node's raw socket: bound to one interface, receiving only the command frame, CAN FD
// frames enabled when the layout says fd. Private to drivers/can_sim.
#pragma once

#include <linux/can.h>

#include <string>

#include "selfsense/drivers/can/can_codec.hpp"
#include "selfsense/drivers/can/can_config.hpp"

namespace selfsense::drivers::can_sim {

// The identifier as the kernel writes it (EFF flag on extended identifiers).
[[nodiscard]] canid_t wire_id(const can::FrameId& frame) noexcept;

// Owns the descriptor; closes it on every way out.
class NodeSocket final {
 public:
  NodeSocket() = default;
  NodeSocket(const NodeSocket&) = delete;
  NodeSocket& operator=(const NodeSocket&) = delete;
  NodeSocket(NodeSocket&&) = delete;
  NodeSocket& operator=(NodeSocket&&) = delete;
  ~NodeSocket();

  // Opens and binds; false with the reason in *error (for "sim-device: <error>").
  [[nodiscard]] bool open(const can::CanConfig& layout, std::string* error);
  [[nodiscard]] int fd() const noexcept { return fd_; }

 private:
  int fd_{-1};
};

}  // namespace selfsense::drivers::can_sim
