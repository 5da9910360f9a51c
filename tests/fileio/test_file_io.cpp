// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: fileio's bounded, non-blocking reads and its atomic, regular-file-only writes.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>

#include "tacse3/fileio/file_io.hpp"

namespace fs = std::filesystem;
namespace fio = tacse3::fileio;

namespace {

class FileIo : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("tacse3-fileio-" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::string s;
  std::getline(in, s, '\0');
  return s;
}

TEST_F(FileIo, ReadsARegularFileWithinItsBound) {
  std::ofstream(dir_ / "a.txt") << "hello";
  std::string text = "untouched";
  EXPECT_TRUE(fio::read_regular_file(dir_ / "a.txt", 5, &text).ok());
  EXPECT_EQ(text, "hello");
  text = "untouched";
  const fio::ReadResult big = fio::read_regular_file(dir_ / "a.txt", 4, &text);
  EXPECT_EQ(big.error, fio::ReadError::kTooLarge);
  EXPECT_EQ(text, "untouched");
  EXPECT_EQ(fio::read_regular_file(dir_ / "none", 5, &text).error, fio::ReadError::kNotFound);
}

TEST_F(FileIo, AFifoADeviceAndADirectoryAreRefusedAtOnce) {
  ASSERT_EQ(::mkfifo((dir_ / "fifo").c_str(), 0600), 0);
  std::string text;
  const auto t0 = std::chrono::steady_clock::now();
  const fio::ReadResult fifo = fio::read_regular_file(dir_ / "fifo", 1024, &text);
  EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(5));
  EXPECT_EQ(fifo.error, fio::ReadError::kNotRegular);
  EXPECT_STREQ(fifo.kind, "a FIFO");
  const fio::ReadResult dev = fio::read_regular_file("/dev/null", 1024, &text);
  EXPECT_EQ(dev.error, fio::ReadError::kNotRegular);
  EXPECT_STREQ(dev.kind, "a character device");
  const fio::ReadResult d = fio::read_regular_file(dir_, 1024, &text);
  EXPECT_EQ(d.error, fio::ReadError::kNotRegular);
  EXPECT_STREQ(d.kind, "a directory");
}

TEST_F(FileIo, WritesReplaceOnlyARegularFileAndKeepItsMode) {
  const fs::path f = dir_ / "out.txt";
  std::string e;
  ASSERT_TRUE(fio::write_file_atomically(f, "one", &e)) << e;
  ASSERT_EQ(::chmod(f.c_str(), 0640), 0);
  ASSERT_TRUE(fio::write_file_atomically(f, "two", &e)) << e;
  EXPECT_EQ(slurp(f), "two");
  struct stat st {};
  ASSERT_EQ(::stat(f.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 07777, 0640u);
  // Nothing but the file is left in the directory: no temporary survives.
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator{}), 1);

  fs::create_symlink(f, dir_ / "link");
  EXPECT_FALSE(fio::write_file_atomically(dir_ / "link", "three", &e));
  EXPECT_NE(e.find("is a symbolic link; refusing to replace it"), std::string::npos) << e;
  EXPECT_TRUE(fs::is_symlink(dir_ / "link"));
  EXPECT_EQ(slurp(f), "two");
  ASSERT_EQ(::mkfifo((dir_ / "fifo").c_str(), 0600), 0);
  EXPECT_FALSE(fio::check_output_file(dir_ / "fifo", &e));
  EXPECT_NE(e.find("is a FIFO"), std::string::npos) << e;
  EXPECT_FALSE(fio::check_output_file("/dev/null", &e));
  EXPECT_NE(e.find("is a character device"), std::string::npos) << e;
  EXPECT_FALSE(fio::check_output_file(dir_ / "missing" / "x", &e));
  EXPECT_NE(e.find("does not exist"), std::string::npos) << e;
}

}  // namespace
