// A private Open MPI session directory per singleton (core/mpi_session_directory.hpp): made and announced before
// MPI starts, left alone under a launcher or a user's own setting, removed at exit; and `tissue` commands started
// side by side, which raced on the shared directory under `ctest -j2`, all start.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include "core/mpi_session_directory.hpp"

namespace fs = std::filesystem;

namespace {

constexpr const char* kVariable = "OMPI_MCA_orte_tmpdir_base";

/// Sets (or, with nullopt, unsets) an environment variable for one test and restores it afterwards.
class ScopedVariable {
 public:
  ScopedVariable(std::string name, const std::optional<std::string>& value) : name_(std::move(name)) {
    if (const char* old = std::getenv(name_.c_str())) old_ = old;
    if (value) setenv(name_.c_str(), value->c_str(), 1);
    else unsetenv(name_.c_str());
  }
  ~ScopedVariable() {
    if (old_) setenv(name_.c_str(), old_->c_str(), 1);
    else unsetenv(name_.c_str());
  }

 private:
  std::string name_;
  std::optional<std::string> old_;
};

class SessionDirectory : public ::testing::Test {
 protected:
  void SetUp() override {
    tmp_ = fs::temp_directory_path() /
           ("tissue_session_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + "_" +
            std::to_string(::getpid()));
    fs::remove_all(tmp_);
    fs::create_directories(tmp_);
    tmpdir_.emplace("TMPDIR", tmp_.string());
    base_.emplace(kVariable, std::nullopt);
    for (const char* launcher : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "PMI_SIZE"})
      launchers_.emplace_back(launcher, std::nullopt);
  }
  void TearDown() override {
    launchers_.clear();
    base_.reset();
    tmpdir_.reset();
    fs::remove_all(tmp_);
  }

  fs::path tmp_;
  std::optional<ScopedVariable> tmpdir_, base_;
  std::vector<ScopedVariable> launchers_;
};

TEST_F(SessionDirectory, MadeUnderTmpdirAnnouncedAndRemovedWithWhatOpenMpiLeft) {
  std::string path;
  {
    const core::SingletonMpiSessionDirectory directory;
    path = directory.path();
    ASSERT_FALSE(path.empty());
    EXPECT_EQ(fs::path(path).parent_path(), tmp_);
    EXPECT_EQ(fs::path(path).filename().string().rfind("tissue-mpi-", 0), 0u) << path;
    EXPECT_TRUE(fs::is_directory(path));
    ASSERT_NE(std::getenv(kVariable), nullptr);
    EXPECT_EQ(std::string(std::getenv(kVariable)), path);
    // What an Open MPI daemon might leave: a session tree with a file in it.
    fs::create_directories(fs::path(path) / "ompi.host.0" / "jf.1");
    std::ofstream(fs::path(path) / "ompi.host.0" / "jf.1" / "contact.txt") << "x";
  }
  EXPECT_FALSE(fs::exists(path)) << path;
}

TEST_F(SessionDirectory, TwoProcessesGetTwoDirectories) {
  const core::SingletonMpiSessionDirectory first;
  base_.emplace(kVariable, std::nullopt);  // as a second, independent process would see it
  const core::SingletonMpiSessionDirectory second;
  EXPECT_FALSE(first.path().empty());
  EXPECT_FALSE(second.path().empty());
  EXPECT_NE(first.path(), second.path());
}

TEST_F(SessionDirectory, LeftToTheLauncherUnderMpirun) {
  const ScopedVariable under_mpirun("OMPI_COMM_WORLD_SIZE", "2");
  const core::SingletonMpiSessionDirectory directory;
  EXPECT_TRUE(directory.path().empty());
  EXPECT_EQ(std::getenv(kVariable), nullptr);
  EXPECT_TRUE(fs::is_empty(tmp_));
}

TEST_F(SessionDirectory, TheUsersOwnSettingIsKept) {
  const ScopedVariable users(kVariable, "/somewhere/else");
  const core::SingletonMpiSessionDirectory directory;
  EXPECT_TRUE(directory.path().empty());
  EXPECT_EQ(std::string(std::getenv(kVariable)), "/somewhere/else");
  EXPECT_TRUE(fs::is_empty(tmp_));
}

TEST_F(SessionDirectory, AnUnwritableTmpdirFallsBackToOpenMpisDefault) {
  tmpdir_.emplace("TMPDIR", (tmp_ / "does_not_exist").string());
  const core::SingletonMpiSessionDirectory directory;
  EXPECT_TRUE(directory.path().empty());
  EXPECT_EQ(std::getenv(kVariable), nullptr);
}

// The race itself: under `ctest -j2` one of two `tissue` processes started at the same moment aborted in MPI_Init
// (open-mpi/ompi#8510). Twelve rounds of six side by side, each a whole MPI start and stop, must all succeed. The
// race is rare (2 in 160 staggered starts of a bare MPI program; none in 180 of `tissue --version`), so the check
// that decides is the last one: $TMPDIR must be empty afterwards. Without the private directory, Open MPI's shared
// one, $TMPDIR/ompi.<host>.<uid>, is left there after a run.
TEST_F(SessionDirectory, TissueCommandsStartedSideBySideAllStart) {
  constexpr int kRounds = 12, kAtOnce = 6;
  for (int round = 0; round < kRounds; ++round) {
    std::vector<pid_t> children;
    for (int i = 0; i < kAtOnce; ++i) {
      const pid_t pid = fork();
      ASSERT_GE(pid, 0);
      if (pid == 0) {
        const std::string log = (tmp_ / ("run_" + std::to_string(round) + "_" + std::to_string(i) + ".log")).string();
        if (!std::freopen(log.c_str(), "w", stdout) || !std::freopen(log.c_str(), "a", stderr)) _exit(127);
        // Staggered by up to 0.1 s, so that one process's MPI_Finalize meets another's MPI_Init: the race (with the
        // shared directory, 2 in 160 such starts failed on the 2-core machine; none at the same instant).
        usleep(static_cast<useconds_t>((37 * i + 13 * round) % 100) * 1000);
        execl(TISSUE_BINARY, TISSUE_BINARY, "--version", static_cast<char*>(nullptr));
        _exit(127);
      }
      children.push_back(pid);
    }
    for (std::size_t i = 0; i < children.size(); ++i) {
      int status = 0;
      ASSERT_EQ(waitpid(children[i], &status, 0), children[i]);
      const fs::path log = tmp_ / ("run_" + std::to_string(round) + "_" + std::to_string(i) + ".log");
      std::ifstream in(log);
      const std::string output((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "round " << round << ", process " << i << ":\n"
                                                                 << output;
      fs::remove(log);
    }
  }
  for (const auto& entry : fs::directory_iterator(tmp_))
    ADD_FAILURE() << "left behind: " << entry.path();
}

}  // namespace
