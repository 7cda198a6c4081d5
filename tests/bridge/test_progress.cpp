// The progress of a long run: one line rewritten on a terminal, plain lines
// into a log, nothing from a short run.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <string>
#include <thread>

#include "bridge/run.hpp"

using gabion::bridge::Progress;
using gabion::bridge::RunContext;

namespace {
// Calls update() `calls` times (the clock is read every 64th call), waiting
// `pause_s` before each read, and returns what went to stdout, the finish()
// included.
std::string printed(const RunContext& ctx, double delay_s, int calls, double pause_s = 0.0) {
  testing::internal::CaptureStdout();
  {
    Progress p(ctx, "test", delay_s);
    for (int k = 1; k <= calls; ++k) {
      if (k % 64 == 0 && pause_s > 0) std::this_thread::sleep_for(std::chrono::duration<double>(pause_s));
      p.update(k, calls, k);
    }
    p.finish();
  }
  return testing::internal::GetCapturedStdout();
}
}  // namespace

TEST(Progress, ALogGetsPlainLinesAndATerminalOneLineRewritten) {
  RunContext ctx;
  ctx.progress = true;
  ctx.progress_log = true;
  ctx.progress_log_interval_s = 0.0;  // (a line at every clock read)
  const std::string log = printed(ctx, 0.0, 64 * 3);
  EXPECT_EQ(log.find('\r'), std::string::npos) << log;
  EXPECT_EQ(std::count(log.begin(), log.end(), '\n'), 3) << log;
  EXPECT_NE(log.find("test 100.0 %"), std::string::npos) << log;

  ctx.progress_log = false;
  const std::string terminal = printed(ctx, 0.0, 64 * 2, 0.3);  // (4 lines a second at most)
  ASSERT_FALSE(terminal.empty());
  EXPECT_EQ(terminal.front(), '\r');
  EXPECT_EQ(terminal.back(), '\n');  // (finish ends the line)
  EXPECT_EQ(std::count(terminal.begin(), terminal.end(), '\r'), 2);
  EXPECT_EQ(std::count(terminal.begin(), terminal.end(), '\n'), 1);
}

TEST(Progress, AShortRunPrintsNothing) {
  RunContext ctx;
  ctx.progress = true;
  ctx.progress_log = true;  // a minute before the first line, whatever the delay asked
  EXPECT_EQ(printed(ctx, 0.0, 64 * 4), "");
  ctx.progress_log = false;
  EXPECT_EQ(printed(ctx, 60.0, 64 * 4), "");
  ctx.progress = false;
  ctx.progress_log = true;
  ctx.progress_log_interval_s = 0.0;
  EXPECT_EQ(printed(ctx, 0.0, 64 * 4), "");
}
