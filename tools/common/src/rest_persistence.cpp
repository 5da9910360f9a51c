// SPDX-License-Identifier: Apache-2.0
// tacse3 tools: how much of the velocity proxy's rate persists once the object rests.
#include "tacse3/tools/rest_persistence.hpp"

#include <algorithm>
#include <cstddef>

namespace tacse3::tools {

double rest_persistence(const std::vector<Eigen::Vector3d>& est,
                        const std::vector<Eigen::Quaterniond>& truth) {
  const std::size_t n = std::min(est.size(), truth.size());
  if (n < 2) return -1.0;
  double peak = 0.0;
  for (std::size_t i = 0; i < n; ++i) peak = std::max(peak, truth[0].angularDistance(truth[i]));
  if (!(peak > 0.0)) return -1.0;
  const double bar = 0.02 * peak;
  std::size_t start = 0;
  while (start < n && truth[0].angularDistance(truth[start]) < bar) ++start;
  std::size_t settle = n;
  while (settle > start && truth[settle - 1].angularDistance(truth[n - 1]) <= bar) --settle;
  double moving = 0.0, rest = 0.0;
  for (std::size_t i = start; i < settle; ++i) moving += est[i].norm();
  const std::size_t rest_from = settle + 12;
  for (std::size_t i = rest_from; i < n; ++i) rest += est[i].norm();
  const std::size_t nm = settle - start, nr = n > rest_from ? n - rest_from : 0;
  if (nm == 0 || nr < 6 || !(moving > 0.0)) return -1.0;
  return (rest / static_cast<double>(nr)) / (moving / static_cast<double>(nm));
}

}  // namespace tacse3::tools
