#pragma once
// Camera frame. Kept apart from measurement.hpp so that only code that handles images pulls in
// OpenCV headers (compile time on 2 cores matters).
//
// Time convention (the estimator's VIO reads `mid_exposure` and nothing else):
//  - a camera path (live driver or recording reader) fills `stamp.sensor` with the camera's own
//    time of the frame, `stamp.host` with the receive time, `exposure` when the camera reports it,
//    and says in `stamp_marks` which instant of the exposure its stamp marks;
//  - the sensor's clock mapping then sets `stamp.mapped` (the stamp on the common timeline, the
//    sensor's time_offset_s included, once), `trigger_time` (start of exposure) and
//    `mid_exposure` (start + exposure / 2) with mid_exposure_time() below. With an unknown
//    exposure (0) all three coincide.
// Recordings (EuRoC/ASL folders, ROS bags, the simulator) stamp the middle of the exposure.

#include <cstdint>
#include <opencv2/core/mat.hpp>

#include "core/time.hpp"

namespace livod {

enum class ImageStampMarks : std::uint8_t {
  mid_exposure,       // recordings, the simulator, cameras that stamp the exposure centre
  start_of_exposure,  // trigger / start-of-exposure stamps (V4L2 SOE, hardware triggers)
  end_of_exposure,    // end-of-exposure / readout stamps
};

struct ImageFrame {
  Stamp stamp;                 // as delivered by the camera path (trigger or frame time)
  cv::Mat image;               // 8-bit mono or BGR
  Nanoseconds exposure{0};     // exposure duration; 0 when unknown
  MappedTime trigger_time;     // start of exposure on the common timeline (when known)
  MappedTime mid_exposure;     // the time the estimator uses: trigger + exposure / 2
  std::uint32_t sequence = 0;  // frame counter from the source (gaps = dropped frames)
  ImageStampMarks stamp_marks = ImageStampMarks::mid_exposure;  // what `stamp` marks
};

// Sets trigger_time and mid_exposure from stamp.mapped, exposure and stamp_marks.
inline void set_exposure_times(ImageFrame& frame) {
  const Nanoseconds half(frame.exposure.count() / 2);
  switch (frame.stamp_marks) {
    case ImageStampMarks::mid_exposure:
      frame.mid_exposure = frame.stamp.mapped;
      frame.trigger_time = frame.stamp.mapped - half;
      break;
    case ImageStampMarks::start_of_exposure:
      frame.trigger_time = frame.stamp.mapped;
      frame.mid_exposure = frame.stamp.mapped + half;
      break;
    case ImageStampMarks::end_of_exposure:
      frame.trigger_time = frame.stamp.mapped - frame.exposure;
      frame.mid_exposure = frame.trigger_time + half;
      break;
  }
}

}  // namespace livod
