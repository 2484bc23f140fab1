#include <freeinit/free_init.h>

#include <stdexcept>

#include "measurement_sequencer.h"
#include "pipeline.h"

namespace freeinit {

// The facade owns its parts: the sequencer that buffers and orders the two streams, and the
// pipeline the configuration selects (joint_pipeline.cpp, paper_pipeline.cpp), which reads the
// sequencer and writes the result.
struct FreeInit::Impl {
  explicit Impl(const FreeInitConfig& c) : cfg(c) {
    cfg.validate();
    pipeline = cfg.estimator.method == EstimatorParams::Method::Joint
                   ? detail::makeJointPipeline(cfg, seq)
                   : detail::makePaperPipeline(cfg, seq);
  }

  void processBuffered() {
    if (done) return;
    const double t0 = detail::wallSeconds();
    done = pipeline->processBuffered(result);
    if (done) result.diag.time_to_result = detail::wallSeconds() - t0;
  }

  void completeMap() {
    if (!done || mapped) return;
    mapped = true;
    const double t0 = detail::wallSeconds();
    pipeline->completeMap(result);
    result.diag.time_map = detail::wallSeconds() - t0;
  }

  FreeInitConfig cfg;
  detail::MeasurementSequencer seq;
  std::unique_ptr<detail::Pipeline> pipeline;
  InitResult result;
  bool done = false;
  bool mapped = false;  ///< result's map is complete (completeMap)
};

FreeInit::FreeInit(const FreeInitConfig& config) : impl_(std::make_unique<Impl>(config)) {}
FreeInit::~FreeInit() = default;
FreeInit::FreeInit(FreeInit&&) noexcept = default;
FreeInit& FreeInit::operator=(FreeInit&&) noexcept = default;

void FreeInit::addImu(const ImuSample& s) {
  impl_->seq.checkImu(s);
  if (impl_->done) return;  // the result is final: nothing more to keep
  impl_->seq.addImu(s);
  impl_->processBuffered();
}

void FreeInit::addFrame(const LidarFrame& f) { addFrame(LidarFrame(f)); }

void FreeInit::addFrame(LidarFrame&& f) {
  if (impl_->done) {  // checked all the same, but not kept (the sequencer checks what it keeps)
    impl_->seq.checkFrame(f);
    return;
  }
  impl_->seq.addFrame(std::move(f));
  impl_->processBuffered();
}

void FreeInit::addFrame(std::shared_ptr<const LidarFrame> f) {
  if (!f) throw std::invalid_argument("LiDAR frame: null");
  if (impl_->done) {
    impl_->seq.checkFrame(*f);
    return;
  }
  impl_->seq.addSharedFrame(std::move(f));
  impl_->processBuffered();
}

void FreeInit::finish() {
  impl_->seq.finish();
  impl_->processBuffered();
}

bool FreeInit::ready() const { return impl_->done; }
const InitResult& FreeInit::result() const {
  impl_->completeMap();
  return impl_->result;
}
const InitResult& FreeInit::resultBeforeMap() const { return impl_->result; }

InitResult FreeInit::run(const FreeInitConfig& config, const std::vector<ImuSample>& imu,
                         const std::vector<LidarFrame>& frames) {
  FreeInit fi(config);
  // Feed in time order, as a recording would interleave them.
  std::size_t k = 0;
  for (const auto& f : frames) {
    const double t_last = f.points.empty() ? f.stamp : f.stamp + f.points.back().time_offset;
    while (k < imu.size() && imu[k].t <= t_last) fi.addImu(imu[k++]);
    if (fi.ready()) break;
    fi.impl_->seq.addBorrowedFrame(f);  // `frames` outlives fi: no copy
    fi.impl_->processBuffered();
    if (fi.ready()) break;
  }
  while (k < imu.size() && !fi.ready()) fi.addImu(imu[k++]);
  if (!fi.ready()) fi.finish();
  fi.impl_->completeMap();
  return std::move(fi.impl_->result);
}

}  // namespace freeinit
