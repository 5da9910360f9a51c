// SPDX-License-Identifier: Apache-2.0
// Tests that the V4L2 backend fails cleanly, with a clear message, when no camera is there.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "tacse3/hal/camera/v4l2_camera.hpp"

namespace tacse3::hal {
namespace {

CameraConfig config(const char* device) {
  CameraConfig c;
  c.device = device;
  return c;
}

bool contains(const CameraStatus& st, const char* text) {
  return std::strstr(st.message(), text) != nullptr;
}

TEST(V4l2Absent, MissingNodeIsNotFoundAndNamesTheDevice) {
  auto cam = make_v4l2_camera(config("/dev/video-nonexistent"));
  const CameraStatus st = cam->open();
  EXPECT_EQ(st.code, CameraError::kNotFound);
  EXPECT_TRUE(contains(st, "/dev/video-nonexistent")) << st.message();
  EXPECT_TRUE(contains(st, "no such device node")) << st.message();
  EXPECT_EQ(cam->link_state(), LinkState::kClosed);
  // Everything after a failed open is a clean error, never a crash.
  EXPECT_EQ(cam->start().code, CameraError::kBadState);
  Frame f;
  EXPECT_EQ(cam->next_frame(f, 10).code, CameraError::kBadState);
  cam->release(f);
  cam->stop();
  EXPECT_EQ(cam->stats().frames, 0u);
  // And it can be tried again.
  EXPECT_EQ(cam->open().code, CameraError::kNotFound);
}

TEST(V4l2Absent, CharacterDeviceThatIsNotV4l2) {
  auto cam = make_v4l2_camera(config("/dev/null"));
  const CameraStatus st = cam->open();
  EXPECT_EQ(st.code, CameraError::kNotSupported);
  EXPECT_TRUE(contains(st, "not a V4L2 device")) << st.message();
}

TEST(V4l2Absent, RegularFileIsNotADevice) {
  char path[] = "/tmp/tacse3-v4l2-XXXXXX";
  const int fd = mkstemp(path);
  ASSERT_GE(fd, 0);
  close(fd);
  auto cam = make_v4l2_camera(config(path));
  const CameraStatus st = cam->open();
  unlink(path);
  EXPECT_EQ(st.code, CameraError::kNotSupported);
  EXPECT_TRUE(contains(st, "not a character device")) << st.message();
}

TEST(V4l2Absent, EmptyDeviceAndBadConfigAreRejectedBeforeTouchingAnything) {
  auto cam = make_v4l2_camera(config(""));
  CameraStatus st = cam->open();
  EXPECT_EQ(st.code, CameraError::kBadConfig);
  EXPECT_TRUE(contains(st, "no device node")) << st.message();

  CameraConfig c = config("/dev/video-nonexistent");
  c.buffer_count = 64;
  st = make_v4l2_camera(c)->open();
  EXPECT_EQ(st.code, CameraError::kBadConfig);
  EXPECT_TRUE(contains(st, "buffer_count")) << st.message();
}

TEST(V4l2Absent, InfoBeforeOpen) {
  auto cam = make_v4l2_camera(config("/dev/video-nonexistent"));
  EXPECT_STREQ(cam->info().backend.data(), "v4l2");
  EXPECT_EQ(cam->info().granted_fps(), 0.0);
  EXPECT_EQ(cam->link_state(), LinkState::kClosed);
}

// A real node, when the machine has one (never on CI): open and close it without streaming.
TEST(V4l2Absent, RealDeviceIfPresent) {
  const char* dev = std::getenv("TACSE3_TEST_V4L2_DEVICE");
  if (dev == nullptr || access(dev, F_OK) != 0) GTEST_SKIP() << "set TACSE3_TEST_V4L2_DEVICE";
  auto cam = make_v4l2_camera(config(dev));
  const CameraStatus st = cam->open();
  ASSERT_TRUE(st.ok()) << st.message();
  const CameraInfo& i = cam->info();
  std::printf("%s: %s %s %dx%d stride %d, %.2f fps granted\n", dev, i.card.data(), i.fourcc.data(),
              i.width, i.height, i.stride_bytes, i.granted_fps());
  cam->stop();
}

}  // namespace
}  // namespace tacse3::hal
