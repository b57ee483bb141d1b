#pragma once
// IMU error model for the simulator: white noise and bias random walk from datasheet-style
// parameters (continuous-time densities), discretised per sample. Deterministic for a seed.

#include <Eigen/Core>
#include <cstdint>
#include <random>

#include "tools/sim/trajectory.hpp"

namespace livod::sim {

struct ImuNoiseParams {
  double rate_hz = 200.0;
  double gyro_noise_density = 1.7e-4;                    // rad/s/sqrt(Hz)   (BMI088-like)
  double accel_noise_density = 2.0e-3;                   // m/s^2/sqrt(Hz)
  double gyro_bias_random_walk = 2.0e-5;                 // rad/s^2/sqrt(Hz)
  double accel_bias_random_walk = 3.0e-4;                // m/s^3/sqrt(Hz)
  Eigen::Vector3d gyro_bias0 = Eigen::Vector3d::Zero();  // initial biases
  Eigen::Vector3d accel_bias0 = Eigen::Vector3d::Zero();
  bool noise_free = false;  // true: exact ideal measurements, biases stay at their initial values

  static ImuNoiseParams ideal(double rate_hz) {
    ImuNoiseParams p;
    p.rate_hz = rate_hz;
    p.noise_free = true;
    return p;
  }
};

class ImuModel {
 public:
  ImuModel(const ImuNoiseParams& params, std::uint64_t seed) : params_(params), rng_(seed) {
    gyro_bias_ = params.gyro_bias0;
    accel_bias_ = params.accel_bias0;
  }

  // One measurement at the true state; advances the bias random walk by one sample period.
  ImuTruth measure(const ImuTruth& truth) {
    if (params_.noise_free) {
      return {truth.gyro_rad_s + gyro_bias_, truth.accel_m_s2 + accel_bias_};
    }
    const double dt = 1.0 / params_.rate_hz;
    const double sqrt_rate = std::sqrt(params_.rate_hz);
    ImuTruth m;
    m.gyro_rad_s =
        truth.gyro_rad_s + gyro_bias_ + params_.gyro_noise_density * sqrt_rate * gauss3();
    m.accel_m_s2 =
        truth.accel_m_s2 + accel_bias_ + params_.accel_noise_density * sqrt_rate * gauss3();
    gyro_bias_ += params_.gyro_bias_random_walk * std::sqrt(dt) * gauss3();
    accel_bias_ += params_.accel_bias_random_walk * std::sqrt(dt) * gauss3();
    return m;
  }

  [[nodiscard]] const Eigen::Vector3d& gyro_bias() const { return gyro_bias_; }
  [[nodiscard]] const Eigen::Vector3d& accel_bias() const { return accel_bias_; }

 private:
  Eigen::Vector3d gauss3() { return {normal_(rng_), normal_(rng_), normal_(rng_)}; }

  ImuNoiseParams params_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
  Eigen::Vector3d gyro_bias_;
  Eigen::Vector3d accel_bias_;
};

}  // namespace livod::sim
