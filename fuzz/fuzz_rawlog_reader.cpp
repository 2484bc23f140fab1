// Fuzz harness: a whole rawlog file (gzip or plain) through the apps' reading path: the rawlog
// reader with its per-record allocation budget (read_budget.h: the program's operator new and
// MRPT's aligned allocator are the guard's, alloc_guard.cpp), MRPT's deserialization with our
// Doppler points map class, the decoder to core types and the record checks. Then the same file
// in salvage mode. Invariants: an error is one line naming the file; records numbered 0, 1, ...;
// what passes the checks is finite, IMU stamps increase, a frame's points are sorted by time;
// salvage reads exactly the records the strict reader read before its error, and reports where it
// stopped.
#include <freeinit/app_support/app_config.h>
#include <freeinit/app_support/ingest.h>
#include <freeinit/app_support/ingest_sources.h>
#include <freeinit/mrpt_plugins/rawlog_reader.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "harness.h"

namespace freeinit::fuzz {
namespace {

// A record may allocate less here than in the apps (256 MB): the same guard, faster executions.
constexpr std::size_t kMaxRecordBytes = std::size_t{32} << 20;

struct Pass {
  std::size_t records = 0, imu = 0, frames = 0, rejected = 0;
  std::string error;  ///< first line of the error that stopped it ("" at a clean end)
  std::string stop;   ///< salvage: where it stopped
};

Pass read(const std::string& path, bool salvage) {
  mrpt_plugins::RawlogIndexPolicy no_index;
  no_index.use = false;
  Pass p;
  app_support::AppConfig config;
  app_support::ObservationDecoder decoder(config.input);
  app_support::RecordChecker checker(config);
  double last_imu = -INFINITY;
  auto inspect = [&](const app_support::CheckedItem& c) {
    if (!c.ok()) {
      ++p.rejected;
      return;
    }
    const auto& it = c.item;
    if (it.kind == app_support::IngestItem::Kind::Imu) {
      if (!std::isfinite(it.imu.t) || !it.imu.gyro.allFinite() || !it.imu.accel.allFinite())
        broken("non-finite IMU sample passed the checks");
      if (!(it.imu.t > last_imu)) broken("IMU stamps passed the checks without increasing");
      last_imu = it.imu.t;
      ++p.imu;
    } else if (it.kind == app_support::IngestItem::Kind::Frame) {
      if (!it.frame || it.frame->points.empty()) broken("empty frame passed the checks");
      for (std::size_t i = 0; i < it.frame->points.size(); ++i) {
        const DopplerPoint& q = it.frame->points[i];
        if (!q.p_l.allFinite() || !std::isfinite(q.doppler) || !std::isfinite(q.time_offset))
          broken("non-finite point passed the checks");
        if (i > 0 && q.time_offset < it.frame->points[i - 1].time_offset)
          broken("frame points not sorted by time");
      }
      ++p.frames;
    }
  };
  try {
    mrpt_plugins::RawlogReader reader(path, no_index);
    reader.setMaxRecordBytes(kMaxRecordBytes);
    reader.setSalvage(salvage);
    // The apps' own loop (what a user's recording goes through), with the record numbering
    // checked on the way.
    app_support::forEachCheckedItem(reader, decoder, checker, inspect,
                                    [&](const mrpt_plugins::RawlogObject& rec) {
                                      if (rec.index != p.records)
                                        broken("records not numbered in order");
                                      ++p.records;
                                    });
    p.stop = reader.salvageStop();
  } catch (const std::exception& e) {
    p.error = e.what();
    if (p.error.empty()) broken("an error without a message");
    if (p.error.find('\n') != std::string::npos) broken("a multi-line error");
  }
  return p;
}

}  // namespace

std::string fuzzOne(const std::uint8_t* data, std::size_t size) {
  std::string error;
  const std::string path = writeInput("rawlog", ".rawlog", data, size, error);
  if (path.empty()) return error;
  const Pass strict = read(path, false);
  if (!strict.error.empty() && strict.error.find(path) == std::string::npos)
    broken("an error that does not name the file");
  const Pass salvaged = read(path, true);
  if (strict.error.empty()) {
    if (!salvaged.error.empty() || !salvaged.stop.empty() || salvaged.records != strict.records)
      broken("salvage differs on a file the strict reader reads whole");
  } else if (salvaged.error.empty() && salvaged.records != strict.records) {
    broken("salvage did not stop where the strict reader failed");
  }
  if (!strict.error.empty()) return "error: " + strict.error;
  return "ok: " + std::to_string(strict.records) + " records, " + std::to_string(strict.imu) +
         " IMU samples, " + std::to_string(strict.frames) + " frames, " +
         std::to_string(strict.rejected) + " rejected";
}

}  // namespace freeinit::fuzz
