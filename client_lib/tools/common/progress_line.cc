#include "progress_line.h"

#include <unistd.h>

#include <utility>

namespace telegrasp::tools {

// Spaces that cover what a longer line shown before `text` leaves to its right.
std::string ProgressLine::padding(const std::string& text) const {
  return open_line_ && last_text_.size() > text.size() ? std::string(last_text_.size() - text.size(), ' ')
                                                       : std::string();
}

ProgressLine::ProgressLine()
    : ProgressLine(stderr, isatty(STDERR_FILENO) != 0, std::chrono::milliseconds(200), std::chrono::seconds(5)) {}

ProgressLine::ProgressLine(std::FILE* out, bool terminal, Clock::duration terminal_period, Clock::duration log_period,
                           std::function<Clock::time_point()> now)
    : out_(out),
      terminal_(terminal),
      terminal_period_(terminal_period),
      log_period_(log_period),
      now_(std::move(now)) {}

bool ProgressLine::due() const { return !written_ || now_() - last_ >= (terminal_ ? terminal_period_ : log_period_); }

void ProgressLine::show(const std::string& text) {
  if (!due()) return;
  if (terminal_)
    std::fprintf(out_, "\r%s%s", text.c_str(), padding(text).c_str());
  else
    std::fprintf(out_, "%s\n", text.c_str());
  wrote(text, terminal_);
}

void ProgressLine::finish(const std::string& text) {
  if (terminal_)
    std::fprintf(out_, "\r%s%s\n", text.c_str(), padding(text).c_str());
  else if (!written_ || text != last_text_)
    std::fprintf(out_, "%s\n", text.c_str());
  wrote(text, false);
}

void ProgressLine::wrote(const std::string& text, bool open_line) {
  std::fflush(out_);
  written_ = true;
  open_line_ = open_line;
  last_ = now_();
  last_text_ = text;
}

void ProgressLine::break_line() {
  if (!open_line_) return;
  std::fputc('\n', out_);
  std::fflush(out_);
  open_line_ = false;
}

}  // namespace telegrasp::tools
