#include <freeinit/mrpt/rawlog_reader.h>
#include <freeinit/mrpt/register.h>
#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/io/CMemoryStream.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/serialization/CArchive.h>

#include <algorithm>
#include <filesystem>
#include <sstream>

namespace freeinit::mrpt_glue {

std::vector<RawlogRecord> readRawlog(const std::string& path, const RawlogReadProgress& progress) {
  registerClasses();
  if (!std::filesystem::is_regular_file(path)) throw InputError(path + ": file not found");

  // Decompress everything (gzip or plain) so that "end of data" is known exactly.
  std::vector<unsigned char> data;
  {
    mrpt::io::CFileGZInputStream f;
    std::string err;
    if (!f.open(path, err)) throw InputError(path + ": cannot open: " + err);
    const auto file_bytes = static_cast<std::size_t>(f.getTotalBytesCount());
    std::vector<unsigned char> chunk(1 << 20);
    for (;;) {
      const std::size_t n = f.Read(chunk.data(), chunk.size());
      if (n == 0) break;
      data.insert(data.end(), chunk.begin(), chunk.begin() + static_cast<std::ptrdiff_t>(n));
      if (progress.inflate)
        progress.inflate(std::min(static_cast<std::size_t>(f.getPosition()), file_bytes),
                         file_bytes);
    }
    if (progress.inflate) progress.inflate(file_bytes, file_bytes);
  }
  if (data.empty()) throw InputError(path + ": empty file (no rawlog records)");

  mrpt::io::CMemoryStream mem;
  mem.assignMemoryNotOwn(data.data(), data.size());
  auto arch = mrpt::serialization::archiveFrom(mem);

  std::vector<RawlogRecord> out;
  for (std::size_t index = 0; mem.getPosition() < data.size(); ++index) {
    const auto start = mem.getPosition();
    mrpt::serialization::CSerializable::Ptr obj;
    try {
      obj = arch.ReadObject();
    } catch (const std::exception& e) {
      // MRPT exceptions carry nested messages and a backtrace: keep the "Message:" lines.
      std::string cause;
      std::istringstream lines(e.what());
      for (std::string l; std::getline(lines, l);) {
        if (l.rfind("Message:", 0) != 0) continue;
        l.erase(0, l.find_first_not_of(' ', 8));
        cause += (cause.empty() ? "" : " <- ") + l;
      }
      if (cause.empty()) cause = e.what();
      const bool at_end = mem.getPosition() >= data.size();
      throw InputError(
          path + ": record " + std::to_string(index) + " (byte " + std::to_string(start) + " of " +
          std::to_string(data.size()) + " decompressed) cannot be read: " +
          (at_end ? "the file ends inside this record (truncated file)"
                  : "corrupted data or a class that is not registered (rawlogs with Doppler "
                    "clouds need the freeinit_mrpt plugin)") +
          ". MRPT: " + cause);
    }
    if (progress.parse) progress.parse(static_cast<std::size_t>(mem.getPosition()), data.size());
    if (!obj) {
      throw InputError(path + ": record " + std::to_string(index) + ": null object");
    }
    if (auto o = std::dynamic_pointer_cast<mrpt::obs::CObservation>(obj)) {
      out.push_back({index, o});
    } else if (auto sf = std::dynamic_pointer_cast<mrpt::obs::CSensoryFrame>(obj)) {
      for (const auto& so : *sf) out.push_back({index, so});
    } else if (std::dynamic_pointer_cast<mrpt::obs::CActionCollection>(obj)) {
      continue;  // odometry actions are not used
    } else {
      throw InputError(path + ": record " + std::to_string(index) + ": unexpected class " +
                       obj->GetRuntimeClass()->className + " in a rawlog");
    }
  }
  return out;
}

}  // namespace freeinit::mrpt_glue
