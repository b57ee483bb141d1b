#pragma once
// Estimator state -> PoseRecord: the one place that knows how the filter's state and covariance
// (estimator/filter/state.hpp) map onto the published pose.

#include <Eigen/Core>
#include <optional>

#include "core/measurement.hpp"
#include "daemon/publish/records.hpp"
#include "estimator/filter/state.hpp"

namespace livod::daemon::publish {

// The pose block of the 19-D error-state covariance: rows/cols kRot..kRot+2 (rotation error, a
// right perturbation R = R_est * Exp(dtheta), body frame) then kPos..kPos+2 (position error,
// world frame), i.e. the [dtheta, dp] order of livod.pose_t.covariance.
[[nodiscard]] Eigen::Matrix<double, 6, 6> pose_covariance(const estimator::StateMatrix& P);

// A pose at time t from a filter state (x, P). `imu`: the body-IMU sample the state was
// propagated with last (its gyro and accelerometer give the angular velocity, gyro - b_g, and the
// world acceleration, R (accel - b_a) + g); without one both are zero. `filter_t`: the time of the
// filter update the state comes from (nullopt before the first update).
[[nodiscard]] PoseRecord pose_record_from_state(const estimator::State& x,
                                                const estimator::StateMatrix& P, MappedTime t,
                                                PoseSource source, PoseStatus status,
                                                std::optional<MappedTime> filter_t,
                                                const ImuSample* imu);

}  // namespace livod::daemon::publish
