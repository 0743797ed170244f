// ProgressLine: a tool's progress on stderr that suits where stderr goes. On a terminal one line
// is rewritten in place ("\r"); in a log file or a pipe a plain line is written every few seconds
// at most, so a long run does not fill its log with progress.
#pragma once

#include <chrono>
#include <cstdio>
#include <functional>
#include <string>

namespace telegrasp::tools {

class ProgressLine {
 public:
  using Clock = std::chrono::steady_clock;

  /// Progress on stderr, rewritten in place if stderr is a terminal (isatty).
  ProgressLine();
  /// Progress on `out`; `terminal` picks the in-place line. On a terminal a line is redrawn at
  /// most every `terminal_period`, elsewhere written at most every `log_period`. `now` is the
  /// clock (tests pass their own).
  ProgressLine(std::FILE* out, bool terminal, Clock::duration terminal_period, Clock::duration log_period,
               std::function<Clock::time_point()> now = Clock::now);

  bool terminal() const { return terminal_; }
  /// Whether show() would write now (so a caller can skip building the text).
  bool due() const;
  /// Writes `text` as the current progress if due().
  void show(const std::string& text);
  /// Writes `text` as the last progress line, whenever it was last written, and ends the line.
  /// Nothing if `text` is what a log already holds last.
  void finish(const std::string& text);
  /// Ends the line being rewritten on a terminal, so that another message can follow on its own
  /// line; nothing elsewhere.
  void break_line();

 private:
  std::string padding(const std::string& text) const;
  // After writing `text`: flushes and remembers it, the line left open or not.
  void wrote(const std::string& text, bool open_line);

  std::FILE* out_;
  bool terminal_;
  Clock::duration terminal_period_, log_period_;
  std::function<Clock::time_point()> now_;
  bool written_ = false;  // a line was written (show or finish)
  bool open_line_ = false;  // on a terminal: a line is shown, not yet ended
  Clock::time_point last_{};
  std::string last_text_;
};

}  // namespace telegrasp::tools
