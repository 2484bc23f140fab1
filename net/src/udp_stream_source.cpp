#include <freeinit/net/stream_source.h>
#include <freeinit/net/udp_socket.h>

#include <ostream>
#include <stdexcept>

namespace freeinit::net {

void printStats(std::ostream& o, const SourceStats& s) {
  printStats(o, s.receiver);
  o << "queue_dropped_imu   = " << s.queue_dropped_imu << "\n"
    << "queue_dropped_frames= " << s.queue_dropped_frames << "\n";
}

UdpStreamSource::UdpStreamSource(const UdpSourceParams& params)
    : params_(params), receiver_(params.receiver) {}

UdpStreamSource::~UdpStreamSource() { stop(); }

void UdpStreamSource::start() {
  if (running_) return;
  socket_ = std::make_unique<UdpSocket>();
  socket_->bind(params_.address, params_.port);
  rcvbuf_ = socket_->setReceiveBuffer(params_.receive_buffer);
  port_ = socket_->localPort();
  running_ = true;
  thread_ = std::thread([this] { loop(); });
}

void UdpStreamSource::stop() {
  running_ = false;
  if (thread_.joinable()) thread_.join();
  socket_.reset();
}

void UdpStreamSource::loop() {
  std::vector<std::uint8_t> buf(65536);
  std::vector<StreamEvent> events;
  try {
    while (running_) {
      const std::optional<std::size_t> n = socket_->receive(buf.data(), buf.size(), 0.01);
      const auto now = SteadyClock::now();
      std::lock_guard<std::mutex> lock(mutex_);
      if (n)  // an empty datagram too: it is counted as malformed (too short)
        receiver_.push(buf.data(), *n, now, events);
      else
        receiver_.tick(now, events);
      enqueue(events);
      events.clear();
    }
  } catch (const std::exception& e) {
    std::lock_guard<std::mutex> lock(mutex_);
    error_ = e.what();
  }
  cv_.notify_all();
}

// Called with mutex_ held.
void UdpStreamSource::enqueue(std::vector<StreamEvent>& events) {
  if (events.empty()) return;
  for (auto& e : events) {
    if (e.kind == StreamEvent::Kind::Frame) {
      if (queued_frames_ >= params_.max_queued_frames) {
        ++stats_.queue_dropped_frames;
        continue;
      }
      ++queued_frames_;
    } else if (e.kind == StreamEvent::Kind::Imu) {
      if (queued_imu_ >= params_.max_queued_imu) {
        ++stats_.queue_dropped_imu;
        continue;
      }
      ++queued_imu_;
    }
    queue_.push_back(std::move(e));
  }
  cv_.notify_all();
}

std::size_t UdpStreamSource::poll(std::vector<StreamEvent>& out, double timeout_s) {
  std::unique_lock<std::mutex> lock(mutex_);
  cv_.wait_for(lock, std::chrono::duration<double>(timeout_s),
               [&] { return !queue_.empty() || !error_.empty() || !running_; });
  if (!error_.empty()) throw std::runtime_error(error_);
  const std::size_t n = queue_.size();
  for (auto& e : queue_) out.push_back(std::move(e));
  queue_.clear();
  queued_frames_ = queued_imu_ = 0;
  return n;
}

SourceStats UdpStreamSource::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  SourceStats s = stats_;
  s.receiver = receiver_.stats();
  return s;
}

}  // namespace freeinit::net
