// SPDX-License-Identifier: Apache-2.0
// tacse3 hal: V4L2 capture backend for UVC sensors (mmap streaming, MJPEG decode, reconnect).
#pragma once

#include <memory>

#include "tacse3/hal/camera.hpp"

namespace tacse3::hal {

// A Camera on a V4L2 video capture node. Nothing touches the device before open().
// Negotiation: see choose_v4l2_format(); 120 fps is requested with VIDIOC_S_PARM and the granted
// interval is reported in CameraInfo. Timestamps come from the driver when it flags them
// CLOCK_MONOTONIC, else from the dequeue time (TimestampSource says which).
std::unique_ptr<Camera> make_v4l2_camera(const CameraConfig& config);

}  // namespace tacse3::hal
