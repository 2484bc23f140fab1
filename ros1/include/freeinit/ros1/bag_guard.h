// Checks on a ROS1 bag made before librosbag and roscpp see it. Both trust the lengths and counts
// written in the file: a record or header field longer than what is left makes
// ros::Header::parse read past its buffer, an index offset into the middle of a chunk or past its
// end makes the message reader do the same, a declared chunk size of 4 GB is allocated as is, and
// roscpp sizes a vector from its declared length before looking at the bytes. A corrupt bag then
// crashes the importer or takes gigabytes, instead of being reported.
//
// checkBagFile walks every record of a bag v2.0 once (the headers only for uncompressed chunks;
// compressed chunks are decompressed, bounded by their declared size) and checks what librosbag
// relies on: every record, header field and data section within the file (or its chunk), the
// fields librosbag reads present with their sizes, the index pointing at message records of known
// connections, chunk sizes that match their data. checkSerialized walks one serialized message of
// the types the importer reads and checks every length and count against the bytes left.
// Neither allocates more than the data they are given can hold.
#pragma once

#include <freeinit/bags/import_stream.h>

#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace freeinit::ros1 {

using bags::BagError;

struct BagGuardLimits {
  /// [bytes] largest chunk (after decompression) accepted. rosbag record writes 768 KB chunks and
  /// one message per chunk above that, so only a single larger message makes a larger chunk: 256
  /// MB is 5 million 48-byte points, beyond any LiDAR frame. A corrupt size field cannot make
  /// either this check or librosbag allocate more.
  std::uint64_t max_chunk_bytes = std::uint64_t{256} << 20;
};

/// Throws BagError "<path>: byte <offset>: <record>: <what is wrong>" on the first inconsistency,
/// and for what the importer cannot read (bag format 1.2, an encrypted or unindexed bag).
void checkBagFile(const std::string& path, const BagGuardLimits& limits = {});

/// What the index of a bag v2.0 says: its connections and, per chunk, the bag times of the
/// messages of each connection (from the index records after the chunk).
struct BagIndex {
  struct Span {
    std::uint64_t first = 0, last = 0;  ///< [ns] bag times of the first and last message
    std::size_t messages = 0;
  };
  struct Chunk {
    std::uint64_t pos = 0;                      ///< [bytes] offset of the chunk record in the file
    std::uint64_t bytes = 0;                    ///< [bytes] the chunk record and its index records
    std::size_t index_records = 0;              ///< index records after the chunk
    std::map<std::uint32_t, Span> connections;  ///< connection id -> its messages in the chunk
  };
  std::map<std::uint32_t, std::string> topics;  ///< connection id -> topic
  std::vector<Chunk> chunks;                    ///< in the order of the chunk info records
};

/// A bag checked piecewise, for reading a time window of it: the constructor reads and checks
/// what librosbag reads when it opens a bag (the file header, the connection and chunk info
/// records at index_pos, each chunk's record header and the index records after it: a few bytes
/// per message, none of the chunks' data); checkChunk() reads and checks one chunk's data as
/// checkBagFile does, before librosbag reads it. Errors: BagError as checkBagFile's.
class CheckedBag {
 public:
  explicit CheckedBag(const std::string& path, const BagGuardLimits& limits = {});
  ~CheckedBag();
  CheckedBag(const CheckedBag&) = delete;
  CheckedBag& operator=(const CheckedBag&) = delete;

  const BagIndex& index() const { return index_; }
  /// Checks chunk `k` of index().chunks (once: later calls return at once).
  void checkChunk(std::size_t k);
  /// Chunks whose data were checked so far.
  std::size_t chunksChecked() const { return checked_count_; }
  /// [bytes] read from the file so far (the index, and the chunks checked).
  std::uint64_t bytesRead() const;

 private:
  struct Impl;
  std::string path_;
  std::unique_ptr<Impl> impl_;
  BagIndex index_;
  std::vector<bool> checked_;
  std::size_t checked_count_ = 0;
};

/// The message types the importer deserializes.
enum class RosMessage { kImu, kPointCloud2, kHeader };

/// Throws std::runtime_error naming the field whose length or count does not fit in the `n` bytes
/// at `data`, or (when `exact`, as for a bag's message record) the number of bytes left over after
/// the message. Returns the message's length.
std::size_t checkSerialized(RosMessage type, const std::uint8_t* data, std::size_t n,
                            bool exact = true);

}  // namespace freeinit::ros1
