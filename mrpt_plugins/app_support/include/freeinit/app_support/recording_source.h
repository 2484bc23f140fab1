// A ROS 2 recording (an MCAP file, a rosbag2 folder, a .db3) read straight in, wherever a rawlog is
// read: its messages go through the importer's reader and stream ([bag_import] of the app's INI;
// bags/ros2_import.h) and come out as the records freeinit-import-bag would have written
// (CObservationIMU, CObservationPointCloud with sensorPose = the extrinsics), so that the ingest
// path, its checks and the result are those of the imported rawlog, to the last digit.
//
// Reading costs the window, not the file: seeking to a start restarts the container's read at
// that log time (less reorder_window and 1 s for clouds logged after their stamp), which the
// MCAP chunk index and the .db3 timestamp index answer without reading what comes before.
#pragma once

#include <freeinit/app_support/app_config.h>
#include <freeinit/mrpt_plugins/rawlog_reader.h>

#include <memory>
#include <string>

namespace freeinit::app_support {

/// True for a path the ROS readers take (by content: ros2::identifyRecording).
bool isRosRecording(const std::string& path);

/// A reader of `path`: the rawlog reader for a rawlog, a RawlogReader over a RecordSource for a
/// ROS 2 recording. For a recording, the extrinsics written as the clouds' sensorPose are the
/// INI's when it gives them (a difference of more than 0.1 deg or 1 mm with /tf_static goes to
/// `warnings`), else those of /tf_static; neither: InputError naming the file. A ROS 1 bag: an
/// InputError saying to import it (freeinit-import-bag) for now.
std::unique_ptr<mrpt_plugins::RawlogReader> openInput(const std::string& path,
                                                      const AppConfig& config,
                                                      const mrpt_plugins::RawlogIndexPolicy& index,
                                                      std::vector<std::string>* warnings);

}  // namespace freeinit::app_support
