// SPDX-License-Identifier: Apache-2.0
// tacse3-bench-accuracy: string assembly by appending, which GCC 12's -O3 -Wrestrict accepts
// (it flags `"literal" + std::string` once inlined).
#pragma once

#include <initializer_list>
#include <string>
#include <string_view>

namespace tacse3::bench_accuracy {

inline std::string cat(std::initializer_list<std::string_view> parts) {
  std::string s;
  for (std::string_view p : parts) s.append(p.data(), p.size());
  return s;
}

inline void append(std::string* o, std::initializer_list<std::string_view> parts) {
  for (std::string_view p : parts) o->append(p.data(), p.size());
}

}  // namespace tacse3::bench_accuracy
