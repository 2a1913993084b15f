// SPDX-License-Identifier: BSD-3-Clause
// The main job on many inputs (a studio's takes): their output folders, their order, how they are
// spread over MPI ranks, and the ranks themselves.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace dp::cli
{

/** One input of a batch: where it is, the output folder name it gets, its size on disk. */
struct BatchInput
{
  std::string path;
  std::string name; // OUTPUT/<name>/: a folder's name, a .series file's folder's, a file's stem
  std::uintmax_t bytes = 0; // what it holds on disk (the frames' files): a proxy for its work
};

/** The inputs with unique names (a repeated name gets -2, -3 ... in the order given), in the
 *  order given. */
std::vector<BatchInput> describeBatch(const std::vector<std::string>& paths);

/** The order the inputs are handed out in: largest first (ties: the order given). */
std::vector<std::size_t> largestFirst(const std::vector<BatchInput>& inputs);

/** The processes of the run: MPI through VTK's controller when the program was started by an
 *  MPI launcher (mpirun sets its environment), else one process and no MPI at all. */
class Ranks
{
public:
  Ranks(int* argc, char*** argv);
  ~Ranks();
  Ranks(const Ranks&) = delete;
  Ranks& operator=(const Ranks&) = delete;

  int rank() const;
  int size() const;
  /** On rank 0: every rank's text, by rank (rank 0's own first); elsewhere: empty. Collective. */
  std::vector<std::string> gather(const std::string& mine) const;
  /** Rank 0's value, on every rank. Collective. */
  int broadcast(int value) const;
  /** Makes the counter takeNext() reads (0 first). Collective. */
  void shareCounter();
  /** The next number of a counter all ranks share (0, 1, 2 ... over the whole run, each number
   *  to one rank): whoever is free takes the next piece of work. Not collective: an MPI atomic
   *  fetch-and-add on rank 0's memory, which needs nothing of rank 0 while it computes. */
  int takeNext();

private:
  struct Impl;
  std::unique_ptr<Impl> P;
};

} // namespace dp::cli
