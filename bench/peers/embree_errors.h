// The Embree peers' error check: the device's last error as an exception naming the call.
#pragma once

#include <embree3/rtcore.h>

#include <stdexcept>
#include <string>

namespace minkq::bench {

inline void check_device(RTCDevice device, const char* what) {
  const RTCError e = rtcGetDeviceError(device);
  if (e != RTC_ERROR_NONE) throw std::runtime_error(std::string("embree: ") + what + " failed (error " + std::to_string(int(e)) + ")");
}

}  // namespace minkq::bench
