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

#include <freeinit/ros1/bag_reader.h>

#include <cstddef>
#include <cstdint>
#include <string>

namespace freeinit::ros1 {

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

/// The message types the importer deserializes.
enum class RosMessage { kImu, kPointCloud2, kHeader };

/// Throws std::runtime_error naming the field whose length or count does not fit in the `n` bytes
/// at `data`, or (when `exact`, as for a bag's message record) the number of bytes left over after
/// the message. Returns the message's length.
std::size_t checkSerialized(RosMessage type, const std::uint8_t* data, std::size_t n,
                            bool exact = true);

}  // namespace freeinit::ros1
