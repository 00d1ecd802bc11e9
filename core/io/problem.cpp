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

}  // namespace bathyslam
