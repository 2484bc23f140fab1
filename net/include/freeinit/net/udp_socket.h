// A minimal POSIX UDP/IPv4 socket (RAII), enough for the live stream: bind and receive with a
// timeout, or send to one destination.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

namespace freeinit::net {

class UdpSocket {
 public:
  UdpSocket();  ///< throws std::runtime_error if no socket can be created
  ~UdpSocket();
  UdpSocket(const UdpSocket&) = delete;
  UdpSocket& operator=(const UdpSocket&) = delete;

  /// Binds to address:port (port 0: an ephemeral port, see localPort()). Throws with the address
  /// and the system's reason on failure (e.g. the port is in use).
  void bind(const std::string& address, std::uint16_t port);
  std::uint16_t localPort() const;
  /// Asks for a receive buffer of `bytes`; returns the size the kernel granted.
  int setReceiveBuffer(int bytes);

  /// Waits up to `timeout_s` for a datagram; returns its size (0 for an empty datagram), nothing
  /// on timeout. Throws on errors.
  std::optional<std::size_t> receive(std::uint8_t* buf, std::size_t capacity, double timeout_s);

  /// Sets the destination of send(). Throws on an invalid address.
  void connect(const std::string& address, std::uint16_t port);
  /// Sends one datagram; returns false if the kernel refused it (e.g. nobody listens yet).
  bool send(const std::uint8_t* data, std::size_t n);

 private:
  int fd_ = -1;
};

/// True if something is bound to address:port (UDP): our own bind fails with "address in use".
/// Lets a sender on the same host wait until its receiver listens.
bool udpPortInUse(const std::string& address, std::uint16_t port);

}  // namespace freeinit::net
