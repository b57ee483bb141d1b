#include "io/euroc_writer.hpp"

#include <iomanip>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>

#include "core/error.hpp"

namespace livod::io {

EurocCameraWriter::EurocCameraWriter(const std::filesystem::path& folder) : folder_(folder) {
  std::error_code ec;
  std::filesystem::create_directories(folder_ / "data", ec);
  if (ec) throw Error("cannot create " + (folder_ / "data").string() + ": " + ec.message());
  csv_.open(folder_ / "data.csv", std::ios::trunc);
  if (!csv_) throw Error("cannot create " + (folder_ / "data.csv").string());
  csv_ << "#timestamp [ns],filename,exposure_ns\n";
}

void EurocCameraWriter::write(SensorTime timestamp, const cv::Mat& image,
                              std::optional<Nanoseconds> exposure) {
  if (last_ && timestamp <= *last_) {
    throw std::invalid_argument("EuRoC camera timestamps must strictly increase");
  }
  const int type = image.type();
  if (image.empty() || (type != CV_8UC1 && type != CV_16UC1 && type != CV_8UC3)) {
    throw std::invalid_argument("EuRoC images are 8/16-bit mono or 8-bit BGR");
  }
  const std::string file = std::to_string(timestamp.ns) + ".png";
  const auto path = folder_ / "data" / file;
  // Fastest zlib level: lossless anyway, and recording must keep up with the camera.
  bool written = false;
  std::string why;
  try {
    written = cv::imwrite(path.string(), image, {cv::IMWRITE_PNG_COMPRESSION, 1});
  } catch (const cv::Exception& e) {
    why = std::string(": ") + e.what();
  }
  if (!written) {
    // A partial file (disk full) is no frame: data.csv never names it, and it goes.
    std::error_code ec;
    std::filesystem::remove(path, ec);
    throw Error("cannot write image " + path.string() + why);
  }
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (!ec) bytes_ += size;
  // Every row has the exposure column (the reader fixes the column count by the first row); 0 is
  // "unknown".
  csv_ << timestamp.ns << ',' << file << ',' << exposure.value_or(Nanoseconds(0)).count() << '\n';
  last_ = timestamp;
  ++frames_;
}

void EurocCameraWriter::flush() {
  csv_.flush();
  if (!csv_) throw Error("cannot write " + (folder_ / "data.csv").string());
}

void write_euroc_camera_yaml(const std::filesystem::path& path, const EurocCameraCalibration& c) {
  std::ofstream os(path);
  if (!os) throw Error("cannot create " + path.string());
  os << std::setprecision(12);
  os << "# livod camera (EuRoC/ASL sensor.yaml layout)\nsensor_type: camera\n"
     << "T_BS:\n  cols: 4\n  rows: 4\n  data: [";
  for (int r = 0; r < 4; ++r) {
    for (int k = 0; k < 4; ++k) os << c.T_body_sensor(r, k) << (r == 3 && k == 3 ? "" : ", ");
  }
  os << "]\nrate_hz: " << c.rate_hz << "\nresolution: [" << c.width << ", " << c.height
     << "]\ncamera_model: pinhole\nintrinsics: [" << c.intrinsics[0] << ", " << c.intrinsics[1]
     << ", " << c.intrinsics[2] << ", " << c.intrinsics[3] << "]\ndistortion_model: ";
  switch (c.distortion_model) {
    case EurocDistortionModel::kRadialTangential:
      os << "radial-tangential";
      break;
    case EurocDistortionModel::kEquidistant:
      os << "equidistant";
      break;
    case EurocDistortionModel::kNone:
      os << "none";
      break;
  }
  os << "\ndistortion_coefficients: [";
  for (std::size_t i = 0; i < c.distortion_coefficients.size(); ++i) {
    os << (i ? ", " : "") << c.distortion_coefficients[i];
  }
  os << "]\n";
  if (!os) throw Error("cannot write " + path.string());
}

}  // namespace livod::io
