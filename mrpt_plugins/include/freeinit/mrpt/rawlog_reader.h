// Reading rawlogs without MRPT's silent truncation: stock tools stop quietly at the first object
// whose class is not registered (or at a cut-off file) and still succeed. This reader decompresses
// the whole file, deserializes object after object and requires the last one to end exactly at
// the end of the data; anything else is an error naming the file and the record index.
#pragma once

#include <mrpt/obs/CObservation.h>

#include <cstddef>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace freeinit::mrpt_glue {

/// A bad input file: the message names the file, the record index and what is wrong.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// One observation and the index of the top-level rawlog record (object) it came from.
struct RawlogRecord {
  std::size_t index = 0;
  mrpt::obs::CObservation::Ptr obs;
};

/// Progress callbacks of readRawlog, each called with (done, total) bytes; either may be empty.
struct RawlogReadProgress {
  std::function<void(std::size_t, std::size_t)> inflate;  ///< file bytes read and decompressed
  std::function<void(std::size_t, std::size_t)> parse;    ///< decompressed bytes deserialized
};

/// Reads a rawlog in either format (observations only, or CSensoryFrame / CActionCollection:
/// sensory frames are flattened, actions skipped). Registers the classes first.
/// Throws InputError on a missing, empty, truncated or corrupted file, or an unregistered class.
std::vector<RawlogRecord> readRawlog(const std::string& path,
                                     const RawlogReadProgress& progress = {});

}  // namespace freeinit::mrpt_glue
