#include "core/io/problem.h"

#include <algorithm>

namespace bathyslam {

std::string Problem::to_string() const {
  std::string out = file;
  if (line > 0) out += ":" + std::to_string(line);
  if (!out.empty()) out += ": ";
  if (severity == Severity::kWarning) out += "warning: ";
  if (!field.empty()) out += field + ": ";
  out += message;
  return out;
}

void ProblemList::error(std::string file, std::size_t line, std::string field,
                        std::string message) {
  ++errors_;
  add({Problem::Severity::kError, std::move(file), line, std::move(field), std::move(message)});
}

void ProblemList::warning(std::string file, std::size_t line, std::string field,
                          std::string message) {
  add({Problem::Severity::kWarning, std::move(file), line, std::move(field), std::move(message)});
}

void ProblemList::add(Problem problem) {
  const auto kept = std::count_if(problems_.begin(), problems_.end(),
                                  [&](const Problem& p) { return p.file == problem.file; });
  if (static_cast<std::size_t>(kept) < max_per_file_) {
    problems_.push_back(std::move(problem));
    return;
  }
  auto it = std::find_if(dropped_.begin(), dropped_.end(),
                         [&](const auto& d) { return d.first == problem.file; });
  if (it == dropped_.end()) {
    dropped_.emplace_back(problem.file, 1);
  } else {
    ++it->second;
  }
}

void ProblemList::append(ProblemList later) {
  errors_ += later.errors_;
  for (Problem& problem : later.problems_) add(std::move(problem));
  for (const std::pair<std::string, std::size_t>& cut : later.dropped_) {
    auto it = std::find_if(dropped_.begin(), dropped_.end(), [&](const auto& d) { return d.first == cut.first; });
    if (it == dropped_.end()) {
      dropped_.push_back(cut);
    } else {
      it->second += cut.second;
    }
  }
}

std::vector<Problem> ProblemList::take() {
  std::vector<Problem> out = std::move(problems_);
  for (const auto& [file, count] : dropped_) {
    out.push_back({Problem::Severity::kError, file, 0, "",
                   std::to_string(count) + " more problems not listed"});
  }
  problems_.clear();
  dropped_.clear();
  return out;
}

namespace {

// Bytes in the UTF-8 sequence that starts at `text[at]`, or 0 if none starts there.
std::size_t utf8_sequence(std::string_view text, std::size_t at) {
  const auto byte = [&](std::size_t i) { return static_cast<unsigned char>(text[i]); };
  const unsigned char lead = byte(at);
  const std::size_t length = lead >= 0xF0 && lead <= 0xF4 ? 4 : lead >= 0xE0 ? 3 : lead >= 0xC2 && lead < 0xE0 ? 2 : 0;
  if (length == 0 || at + length > text.size()) return 0;
  for (std::size_t i = at + 1; i < at + length; ++i)
    if ((byte(i) & 0xC0) != 0x80) return 0;
  // Overlong forms, UTF-16 surrogates and code points past U+10FFFF are not UTF-8 either.
  const unsigned char second = byte(at + 1);
  if ((lead == 0xE0 && second < 0xA0) || (lead == 0xED && second > 0x9F) || (lead == 0xF0 && second < 0x90) ||
      (lead == 0xF4 && second > 0x8F))
    return 0;
  return length;
}

}  // namespace

std::string printable(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (std::size_t at = 0; at < text.size();) {
    const unsigned char c = static_cast<unsigned char>(text[at]);
    if (c >= 0x20 && c < 0x7F) {
      out += static_cast<char>(c);
      ++at;
    } else if (const std::size_t length = c >= 0x80 ? utf8_sequence(text, at) : 0; length > 0) {
      out.append(text.substr(at, length));
      at += length;
    } else {
      constexpr char kHex[] = "0123456789abcdef";
      out += "\\x";
      out += kHex[c >> 4];
      out += kHex[c & 0xF];
      ++at;
    }
  }
  return out;
}

std::string quoted_input(std::string_view text) {
  if (text.size() <= kQuotedBytes) return "'" + printable(text) + "'";
  // Cut before a UTF-8 sequence rather than inside it (at most 3 continuation bytes back).
  std::size_t cut = kQuotedBytes;
  for (int back = 0; back < 3 && (static_cast<unsigned char>(text[cut]) & 0xC0) == 0x80; ++back) --cut;
  return "'" + printable(text.substr(0, cut)) + "\u2026' (" + std::to_string(text.size()) + " bytes)";
}

}  // namespace bathyslam
