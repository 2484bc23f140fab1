#include <arpa/inet.h>
#include <freeinit/net/udp_socket.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace freeinit::net {
namespace {

sockaddr_in makeAddress(const std::string& address, std::uint16_t port) {
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  if (inet_pton(AF_INET, address.c_str(), &a.sin_addr) != 1)
    throw std::invalid_argument("'" + address + "' is not an IPv4 address");
  return a;
}

std::string where(const std::string& address, std::uint16_t port) {
  return address + ":" + std::to_string(port);
}

}  // namespace

UdpSocket::UdpSocket() : fd_(::socket(AF_INET, SOCK_DGRAM, 0)) {
  if (fd_ < 0)
    throw std::runtime_error(std::string("cannot create a UDP socket: ") + std::strerror(errno));
}

UdpSocket::~UdpSocket() { ::close(fd_); }

void UdpSocket::bind(const std::string& address, std::uint16_t port) {
  const sockaddr_in a = makeAddress(address, port);
  if (::bind(fd_, reinterpret_cast<const sockaddr*>(&a), sizeof(a)) != 0)
    throw std::runtime_error("cannot listen on UDP " + where(address, port) + ": " +
                             std::strerror(errno));
}

std::uint16_t UdpSocket::localPort() const {
  sockaddr_in a{};
  socklen_t len = sizeof(a);
  if (::getsockname(fd_, reinterpret_cast<sockaddr*>(&a), &len) != 0) return 0;
  return ntohs(a.sin_port);
}

int UdpSocket::setReceiveBuffer(int bytes) {
  // SO_RCVBUFFORCE exceeds net.core.rmem_max when privileged; otherwise the capped request.
  if (::setsockopt(fd_, SOL_SOCKET, SO_RCVBUFFORCE, &bytes, sizeof(bytes)) != 0)
    ::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &bytes, sizeof(bytes));
  int granted = 0;
  socklen_t len = sizeof(granted);
  ::getsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &granted, &len);
  return granted;
}

std::optional<std::size_t> UdpSocket::receive(std::uint8_t* buf, std::size_t capacity,
                                              double timeout_s) {
  pollfd p{fd_, POLLIN, 0};
  const int r = ::poll(&p, 1, static_cast<int>(timeout_s * 1000.0));
  if (r < 0) {
    if (errno == EINTR) return std::nullopt;
    throw std::runtime_error(std::string("poll on the UDP socket failed: ") + std::strerror(errno));
  }
  if (r == 0) return std::nullopt;
  const ssize_t n = ::recv(fd_, buf, capacity, MSG_TRUNC);
  if (n < 0) {
    if (errno == EINTR || errno == EAGAIN || errno == ECONNREFUSED) return std::nullopt;
    throw std::runtime_error(std::string("UDP receive failed: ") + std::strerror(errno));
  }
  // A datagram larger than the buffer is cut: its length fields no longer match, the decoder
  // rejects it.
  return std::min(static_cast<std::size_t>(n), capacity);
}

void UdpSocket::connect(const std::string& address, std::uint16_t port) {
  const sockaddr_in a = makeAddress(address, port);
  if (::connect(fd_, reinterpret_cast<const sockaddr*>(&a), sizeof(a)) != 0)
    throw std::runtime_error("cannot address UDP " + where(address, port) + ": " +
                             std::strerror(errno));
}

bool UdpSocket::send(const std::uint8_t* data, std::size_t n) {
  for (;;) {
    const ssize_t r = ::send(fd_, data, n, 0);
    if (r == static_cast<ssize_t>(n)) return true;
    if (r < 0 && errno == EINTR) continue;
    if (r < 0 && (errno == ENOBUFS || errno == EAGAIN)) {
      ::usleep(100);  // the local queue is full: wait for it, as a real link would
      continue;
    }
    return false;
  }
}

bool udpPortInUse(const std::string& address, std::uint16_t port) {
  UdpSocket s;
  try {
    s.bind(address, port);
  } catch (const std::runtime_error&) {
    return true;
  }
  return false;
}

}  // namespace freeinit::net
