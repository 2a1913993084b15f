// SPDX-License-Identifier: BSD-3-Clause
// What the main job says on the terminal: VTK's messages as single lines, a progress bar, and
// Ctrl-C, which stops a filter between frames.
#pragma once

#include "vtkAlgorithm.h"
#include "vtkCommand.h"

#include <cmath>
#include <csignal>
#include <cstdio>
#include <iostream>
#include <string>
#include <unistd.h>

namespace dp::cli
{

/** Set by the SIGINT and SIGTERM handler: the run stops after the frame under way. */
inline volatile std::sig_atomic_t Interrupted = 0;

// Turns VTK errors and warnings into single lines on stderr and counts the errors.
class MessagePrinter : public vtkCommand
{
public:
  static MessagePrinter* New() { return new MessagePrinter; }
  void Execute(vtkObject*, unsigned long event, void* callData) override
  {
    const char* text = static_cast<const char*>(callData);
    std::string line = text ? text : "";
    // VTK prefixes "ERROR: In <source file>, line N\n<class> (<address>): "; keep the message.
    const std::size_t colon = line.find("): ");
    if (colon != std::string::npos)
      line = line.substr(colon + 3);
    while (!line.empty() && (line.back() == '\n' || line.back() == ' '))
      line.pop_back();
    if (ProgressShown)
      std::cerr << "\r\033[K";
    std::cerr << (event == vtkCommand::ErrorEvent ? "error: " : "warning: ") << line << "\n";
    if (event == vtkCommand::ErrorEvent)
      ++Errors;
  }
  int Errors = 0;
  bool ProgressShown = false;
};

// A one-line progress bar on stderr, drawn only when stderr is a terminal.
class ProgressBar
{
public:
  explicit ProgressBar(bool enabled) : Enabled(enabled && isatty(STDERR_FILENO)) {}
  void show(const std::string& what, double fraction)
  {
    if (!Enabled)
      return;
    const int width = 30, filled = static_cast<int>(std::lround(width * fraction));
    std::fprintf(stderr, "\r\033[K%-24s [%s%s] %3d%%", what.c_str(),
                 std::string(filled, '#').c_str(), std::string(width - filled, '.').c_str(),
                 static_cast<int>(std::lround(100 * fraction)));
    std::fflush(stderr);
  }
  void clear()
  {
    if (Enabled)
      std::fprintf(stderr, "\r\033[K");
  }
  bool enabled() const { return Enabled; }

private:
  bool Enabled;
};

// Aborts a filter when Ctrl-C was pressed, and moves the progress bar.
class ProgressWatcher : public vtkCommand
{
public:
  static ProgressWatcher* New() { return new ProgressWatcher; }
  void Execute(vtkObject* caller, unsigned long, void* callData) override
  {
    if (Interrupted)
      static_cast<vtkAlgorithm*>(caller)->SetAbortExecute(1);
    else if (Bar)
      Bar->show(What, *static_cast<double*>(callData));
  }
  ProgressBar* Bar = nullptr;
  std::string What;
};

} // namespace dp::cli
