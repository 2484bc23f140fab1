#include <freeinit/mrpt_plugins/points_map_doppler.h>
#include <freeinit/mrpt_plugins/read_budget.h>
#include <mrpt/core/bits_mem.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/serialization/CArchive.h>

#include <algorithm>

namespace freeinit::mrpt_plugins {

IMPLEMENTS_SERIALIZABLE(CPointsMapDoppler, CPointsMap, freeinit::mrpt_plugins)

void CPointsMapDoppler::insertPointDoppler(float x, float y, float z, float doppler,
                                           float time_offset, float intensity, std::uint16_t line) {
  m_x.push_back(x);
  m_y.push_back(y);
  m_z.push_back(z);
  doppler_.push_back(doppler);
  time_offset_.push_back(time_offset);
  intensity_.push_back(intensity);
  line_.push_back(line);
  mark_as_modified();
}

void CPointsMapDoppler::reserve(size_t n) {
  m_x.reserve(n);
  m_y.reserve(n);
  m_z.reserve(n);
  doppler_.reserve(n);
  time_offset_.reserve(n);
  intensity_.reserve(n);
  line_.reserve(n);
}

void CPointsMapDoppler::resize(size_t n) {
  m_x.resize(n, 0);
  m_y.resize(n, 0);
  m_z.resize(n, 0);
  doppler_.resize(n, 0);
  time_offset_.resize(n, 0);
  intensity_.resize(n, 0);
  line_.resize(n, 0);
  mark_as_modified();
}

void CPointsMapDoppler::setSize(size_t n) {
  m_x.assign(n, 0);
  m_y.assign(n, 0);
  m_z.assign(n, 0);
  doppler_.assign(n, 0);
  time_offset_.assign(n, 0);
  intensity_.assign(n, 0);
  line_.assign(n, 0);
  mark_as_modified();
}

void CPointsMapDoppler::insertPointFast(float x, float y, float z) {
  m_x.push_back(x);
  m_y.push_back(y);
  m_z.push_back(z);
  doppler_.push_back(0);
  time_offset_.push_back(0);
  intensity_.push_back(0);
  line_.push_back(0);
}

void CPointsMapDoppler::getPointAllFieldsFast(size_t i, std::vector<float>& d) const {
  d.resize(kFieldCount);
  d[0] = m_x[i];
  d[1] = m_y[i];
  d[2] = m_z[i];
  d[3] = doppler_[i];
  d[4] = time_offset_[i];
  d[5] = intensity_[i];
  d[6] = static_cast<float>(line_[i]);
}

void CPointsMapDoppler::setPointAllFieldsFast(size_t i, const std::vector<float>& d) {
  ASSERT_EQUAL_(d.size(), kFieldCount);
  m_x[i] = d[0];
  m_y[i] = d[1];
  m_z[i] = d[2];
  doppler_[i] = d[3];
  time_offset_[i] = d[4];
  intensity_[i] = d[5];
  line_[i] = static_cast<std::uint16_t>(d[6]);
}

// Range scans carry no Doppler: load their geometry through a stock map, extra fields zero.
void CPointsMapDoppler::loadFromRangeScan(const mrpt::obs::CObservation2DRangeScan& scan,
                                          const std::optional<const mrpt::poses::CPose3D>& pose) {
  mrpt::maps::CSimplePointsMap tmp;
  tmp.insertionOptions = insertionOptions;
  tmp.loadFromRangeScan(scan, pose);
  impl_copyFrom(tmp);
}

void CPointsMapDoppler::loadFromRangeScan(const mrpt::obs::CObservation3DRangeScan& scan,
                                          const std::optional<const mrpt::poses::CPose3D>& pose) {
  mrpt::maps::CSimplePointsMap tmp;
  tmp.insertionOptions = insertionOptions;
  tmp.loadFromRangeScan(scan, pose);
  impl_copyFrom(tmp);
}

void CPointsMapDoppler::impl_copyFrom(const mrpt::maps::CPointsMap& obj) {
  base_copyFrom(obj);  // copies XYZ and calls resize(N): extra fields are zero-filled
  if (const auto* o = dynamic_cast<const CPointsMapDoppler*>(&obj); o != nullptr && o != this) {
    doppler_ = o->doppler_;
    time_offset_ = o->time_offset_;
    intensity_ = o->intensity_;
    line_ = o->line_;
  }
}

void CPointsMapDoppler::addFrom_classSpecific(const mrpt::maps::CPointsMap& other,
                                              size_t nPreviousPoints, bool filterOutPointsAtZero) {
  const auto* o = dynamic_cast<const CPointsMapDoppler*>(&other);
  // With filtering, the copied points can no longer be matched to their source index.
  if (o == nullptr || filterOutPointsAtZero || nPreviousPoints + o->size() != size()) return;
  for (size_t i = 0; i < o->size(); ++i) {
    const size_t j = nPreviousPoints + i;
    doppler_[j] = o->doppler_[i];
    time_offset_[j] = o->time_offset_[i];
    intensity_[j] = o->intensity_[i];
    line_[j] = o->line_[i];
  }
}

void CPointsMapDoppler::internal_clear() {
  mrpt::vector_strong_clear(m_x);
  mrpt::vector_strong_clear(m_y);
  mrpt::vector_strong_clear(m_z);
  mrpt::vector_strong_clear(doppler_);
  mrpt::vector_strong_clear(time_offset_);
  mrpt::vector_strong_clear(intensity_);
  mrpt::vector_strong_clear(line_);
  mark_as_modified();
}

uint8_t CPointsMapDoppler::serializeGetVersion() const { return 0; }

void CPointsMapDoppler::serializeTo(mrpt::serialization::CArchive& out) const {
  const auto n = static_cast<uint32_t>(m_x.size());
  out << n;
  if (n > 0) {
    out.WriteBufferFixEndianness(m_x.data(), n);
    out.WriteBufferFixEndianness(m_y.data(), n);
    out.WriteBufferFixEndianness(m_z.data(), n);
    out.WriteBufferFixEndianness(doppler_.data(), n);
    out.WriteBufferFixEndianness(time_offset_.data(), n);
    out.WriteBufferFixEndianness(intensity_.data(), n);
    out.WriteBufferFixEndianness(line_.data(), n);
  }
  insertionOptions.writeToStream(out);
  likelihoodOptions.writeToStream(out);
}

namespace {

/// Reads `n` values into `v` a chunk at a time: what is allocated follows what the stream really
/// holds, so a corrupt count fails where the data end instead of at the allocator (MRPT's aligned
/// allocator returns null rather than throwing).
template <class Vec>
void readChunked(mrpt::serialization::CArchive& in, Vec& v, std::size_t n) {
  constexpr std::size_t kChunk = std::size_t{1} << 16;
  v.clear();
  // Where the reader's budget vouches for the count (a count the rest of the file may hold),
  // the whole vector at once: growing it charges its earlier blocks too, and a valid cloud of
  // millions of points would look twice its size.
  if (ReadBudget::fits(n * sizeof(typename Vec::value_type))) v.reserve(n);
  for (std::size_t done = 0; done < n;) {
    const std::size_t k = std::min(kChunk, n - done);
    v.resize(done + k);
    in.ReadBufferFixEndianness(v.data() + done, k);
    done += k;
  }
}

}  // namespace

void CPointsMapDoppler::serializeFrom(mrpt::serialization::CArchive& in, uint8_t version) {
  switch (version) {
    case 0: {
      uint32_t n = 0;
      in >> n;
      if (n > kMaxPoints)
        THROW_EXCEPTION_FMT("%u points declared for one cloud, at most %u are read",
                            static_cast<unsigned>(n), static_cast<unsigned>(kMaxPoints));
      readChunked(in, m_x, n);
      readChunked(in, m_y, n);
      readChunked(in, m_z, n);
      readChunked(in, doppler_, n);
      readChunked(in, time_offset_, n);
      readChunked(in, intensity_, n);
      readChunked(in, line_, n);
      insertionOptions.readFromStream(in);
      likelihoodOptions.readFromStream(in);
      mark_as_modified();
    } break;
    default:
      MRPT_THROW_UNKNOWN_SERIALIZATION_VERSION(version);
  }
}

}  // namespace freeinit::mrpt_plugins
