// SPDX-License-Identifier: Apache-2.0
// Tests that the libcamera backend fails cleanly when the requested camera does not exist.
#include <gtest/gtest.h>

#include <cstring>

#include "tacse3/hal/camera/libcamera_camera.hpp"

namespace tacse3::hal {
namespace {

TEST(LibcameraAbsent, UnknownIdIsNotFound) {
  CameraConfig c;
  c.device = "/base/no/such/camera@10";
  auto cam = make_libcamera_camera(c);
  const CameraStatus st = cam->open();
  if (st.code == CameraError::kIo) GTEST_SKIP() << "libcamera cannot start here: " << st.message();
  EXPECT_EQ(st.code, CameraError::kNotFound);
  EXPECT_NE(std::strstr(st.message(), "/base/no/such/camera@10"), nullptr) << st.message();
  EXPECT_EQ(cam->link_state(), LinkState::kClosed);
  Frame f;
  EXPECT_EQ(cam->next_frame(f, 5).code, CameraError::kBadState);
  cam->stop();
}

TEST(LibcameraAbsent, IndexBeyondTheCamerasIsNotFound) {
  CameraConfig c;
  c.device = "#7";
  auto cam = make_libcamera_camera(c);
  const CameraStatus st = cam->open();
  if (st.code == CameraError::kIo) GTEST_SKIP() << "libcamera cannot start here: " << st.message();
  EXPECT_EQ(st.code, CameraError::kNotFound);
  EXPECT_NE(std::strstr(st.message(), "#7"), nullptr) << st.message();
}

TEST(LibcameraAbsent, TwoCamerasShareOneManager) {
  // libcamera aborts on a second CameraManager; two backends must coexist.
  CameraConfig c;
  c.device = "#5";
  auto a = make_libcamera_camera(c);
  auto b = make_libcamera_camera(c);
  const CameraStatus sa = a->open();
  const CameraStatus sb = b->open();
  if (sa.code == CameraError::kIo) GTEST_SKIP() << sa.message();
  EXPECT_EQ(sa.code, CameraError::kNotFound);
  EXPECT_EQ(sb.code, CameraError::kNotFound);
}

TEST(LibcameraAbsent, BadConfigBeforeTheManager) {
  CameraConfig c;
  c.fps = 0;
  EXPECT_EQ(make_libcamera_camera(c)->open().code, CameraError::kBadConfig);
}

}  // namespace
}  // namespace tacse3::hal
