#include "node_socket.hpp"

#include <linux/can/raw.h>
#include <linux/sockios.h>
#include <net/if.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>

#include "selfsense/base/errno_text.hpp"

namespace selfsense::drivers::can_sim {

canid_t wire_id(const can::FrameId& frame) noexcept {
  return frame.extended ? (frame.id & CAN_EFF_MASK) | CAN_EFF_FLAG : frame.id & CAN_SFF_MASK;
}

NodeSocket::~NodeSocket() {
  if (fd_ >= 0) ::close(fd_);
}

bool NodeSocket::open(const can::CanConfig& layout, std::string* error) {
  fd_ = ::socket(PF_CAN, SOCK_RAW, CAN_RAW);
  if (fd_ < 0) {
    *error = std::string("socket(PF_CAN): ") + base::errno_text(errno) +
             " (a kernel without SocketCAN? modprobe can can_raw)";
    return false;
  }
  ifreq ifr{};
  static_cast<void>(
      std::snprintf(ifr.ifr_name, sizeof(ifr.ifr_name), "%s", layout.interface.c_str()));
  if (::ioctl(fd_, SIOCGIFINDEX, &ifr) < 0) {
    *error = "--can " + layout.interface + ": " + base::errno_text(errno);
    return false;
  }
  const int index = ifr.ifr_ifindex;
  if (layout.fd) {
    const int on = 1;
    if (::ioctl(fd_, SIOCGIFMTU, &ifr) < 0 || ifr.ifr_mtu != static_cast<int>(CANFD_MTU) ||
        ::setsockopt(fd_, SOL_CAN_RAW, CAN_RAW_FD_FRAMES, &on, sizeof(on)) < 0) {
      *error = "--can " + layout.interface + ": CAN FD (driver.fd) needs MTU 72";
      return false;
    }
  }
  const can::FrameId command_id = layout.command.frame;
  can_filter filter{wire_id(command_id), (command_id.extended ? CAN_EFF_MASK : CAN_SFF_MASK) |
                                             CAN_EFF_FLAG | CAN_RTR_FLAG};
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = index;
  if (::setsockopt(fd_, SOL_CAN_RAW, CAN_RAW_FILTER, &filter, sizeof(filter)) < 0 ||
      ::bind(fd_, reinterpret_cast<const sockaddr*>(&addr), sizeof(addr)) < 0) {
    *error = "--can " + layout.interface + ": bind: " + base::errno_text(errno);
    return false;
  }
  return true;
}

}  // namespace selfsense::drivers::can_sim
