#pragma once
// A PM QoS CPU latency request (realtime.cpu_dma_latency_us): while the object lives, the kernel's
// cpuidle keeps every CPU in idle states whose exit latency is at most the requested value
// (Documentation/power/pm_qos_interface.rst: write the value to /dev/cpu_dma_latency and keep the
// file open; closing it ends the request). 0 keeps idle CPUs polling instead of halting.
//
// Why livod offers it: an IMU-rate pose crosses three threads (capture, scheduler, publisher), and
// each hand-over may wake a halted CPU. Under a hypervisor a halted vCPU is a VM exit, and waking
// it takes the host's scheduler: milliseconds at the tail (docs/daemon.md "Latency"). A robot's
// computer with deep C-states pays the same, in smaller amounts. The price is power: a polling
// idle CPU does not sleep. A refusal (no permission, no such device) is reported, never fatal.

#include <filesystem>
#include <string>

namespace livod::daemon::runtime {

class CpuLatencyRequest {
 public:
  // The kernel's interface; a test passes another file.
  static constexpr const char* kDevice = "/dev/cpu_dma_latency";

  CpuLatencyRequest() = default;  // no request
  // Requests at most `max_latency_us` (>= 0) of CPU wake-up latency through `device`.
  explicit CpuLatencyRequest(int max_latency_us, const std::filesystem::path& device = kDevice);
  ~CpuLatencyRequest();
  CpuLatencyRequest(CpuLatencyRequest&& other) noexcept;
  CpuLatencyRequest& operator=(CpuLatencyRequest&& other) noexcept;
  CpuLatencyRequest(const CpuLatencyRequest&) = delete;
  CpuLatencyRequest& operator=(const CpuLatencyRequest&) = delete;

  // The request holds (the device is open and took the value).
  [[nodiscard]] bool active() const noexcept { return fd_ >= 0; }
  // Why a request was not made (empty when active or when none was asked for).
  [[nodiscard]] const std::string& refusal() const noexcept { return refusal_; }

 private:
  void release() noexcept;

  int fd_ = -1;
  std::string refusal_;
};

}  // namespace livod::daemon::runtime
