// SPDX-License-Identifier: Apache-2.0
// tacse3 hal: libcamera capture backend for CSI sensors and other libcamera pipelines.
#pragma once

#include <memory>

#include "tacse3/hal/camera.hpp"

namespace tacse3::hal {

// A Camera on a libcamera camera (CameraConfig::device: id, "#N", or empty for the first).
// All Requests and FrameBuffers are made at open() and reused (Request::ReuseBuffers); the frame
// rate is pinned with FrameDurationLimits = {1e6/fps, 1e6/fps} us (8333 us at 120 fps); frame
// timestamps are the SensorTimestamp metadata. requestCompleted runs on libcamera's thread and
// only pushes the request index into a lock-free ring and signals an eventfd; next_frame()
// drains it on the capture thread. All cameras of the process share one CameraManager.
std::unique_ptr<Camera> make_libcamera_camera(const CameraConfig& config);

}  // namespace tacse3::hal
