// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: keeps the support library non-empty when no helper sources exist.
namespace tacse3::test {
int support_library_anchor() {
  return 0;
}
}  // namespace tacse3::test
