// SPDX-License-Identifier: BSD-3-Clause
/**
 * The memory one file may take when it is read. Every reader checks what a file's counts would
 * make it allocate against what the file's bytes can hold before it allocates (each reader's
 * comment states its worst case per input byte); a compressed file (a .dpz, a zstd, LZF or Draco
 * section) can still hold a take far larger than itself, so a decoder adds up what the decoded
 * take will hold, from its counts alone, and asks the budget before allocating any of it.
 *
 * The budget is 8 GiB, or the environment variable DP_MEMORY_BUDGET: bytes, or a number with
 * K, M, G or T (binary units), e.g. DP_MEMORY_BUDGET=24G. A file over it is refused with a
 * dp::FileError naming the file, what it needs and the budget; nothing is allocated for it.
 */
#ifndef dp_io_MemoryBudget_h
#define dp_io_MemoryBudget_h

#include <cstdint>
#include <string>

namespace dp
{

/** The default budget: 8 GiB. */
constexpr std::uint64_t DefaultMemoryBudget = std::uint64_t{8} << 30;

/** DP_MEMORY_BUDGET when it is set, else the default; a malformed value throws
 *  std::invalid_argument naming the variable. */
std::uint64_t memoryBudget();

/** "1.5 GiB", "320 MiB", "12 KiB", "100 bytes". */
std::string formatBytes(double bytes);

/**
 * What decoding one file will hold, added up section by section before each is allocated: each
 * claim that brings the total over the budget throws dp::FileError naming `path`, the claim, the
 * total and the budget, and how to raise it.
 */
class MemoryAccount
{
public:
  explicit MemoryAccount(std::string path, std::uint64_t budget = memoryBudget());
  /** Adds `bytes` (a double: counts from a hostile header may overflow any integer) for `what`. */
  void claim(double bytes, const std::string& what);
  double claimed() const { return Claimed; }
  std::uint64_t budget() const { return Budget; }

private:
  std::string Path;
  std::uint64_t Budget;
  double Claimed = 0;
};

} // namespace dp

#endif
