#include "io/input_loss.hpp"

#include <cstdio>

namespace livod::io {

std::string format_loss(const InputLoss& loss) {
  std::string out = loss.file + ": ";
  if (loss.byte_offset) out += "at byte offset " + std::to_string(*loss.byte_offset) + ": ";
  out += loss.reason + "; skipped ";
  std::string parts;
  const auto add = [&parts](const std::string& part) {
    parts += (parts.empty() ? "" : ", ") + part;
  };
  if (loss.bytes > 0) add(std::to_string(loss.bytes) + " bytes");
  if (loss.records > 0) {
    add((loss.records_estimated ? "about " : "") + std::to_string(loss.records) + " " + loss.unit);
  } else {
    add("an unknown number of " + loss.unit);
  }
  if (loss.seconds) {
    char text[64];
    std::snprintf(text, sizeof text, "%.3f s of recording", *loss.seconds);
    add(text);
  }
  return out + parts;
}

void InputLossLog::add(InputLoss loss) {
  ++count_;
  bytes_ += loss.bytes;
  records_ += loss.records;
  if (loss.seconds) seconds_ += *loss.seconds;
  last_listed_ = entries_.size() < kMaxEntries;
  if (last_listed_) entries_.push_back(std::move(loss));
}

void InputLossLog::merge(const InputLossLog& other) {
  for (const InputLoss& loss : other.entries_) {
    if (entries_.size() < kMaxEntries) entries_.push_back(loss);
  }
  count_ += other.count_;
  bytes_ += other.bytes_;
  records_ += other.records_;
  seconds_ += other.seconds_;
  last_listed_ = false;
}

void InputLossLog::set_last_seconds(double seconds) {
  if (count_ == 0) return;
  seconds_ += seconds;
  if (last_listed_ && !entries_.empty()) {
    if (entries_.back().seconds) seconds_ -= *entries_.back().seconds;
    entries_.back().seconds = seconds;
  }
}

}  // namespace livod::io
