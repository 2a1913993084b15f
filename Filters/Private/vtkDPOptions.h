// SPDX-License-Identifier: BSD-3-Clause
// The filters' generic option accessors over an engine option table (private to the module):
// SetTrackerOption, SetCompressionOption and the writer's.
#ifndef vtkDPOptions_h
#define vtkDPOptions_h

#include "dp/io/OptionTable.h"

#include <stdexcept>
#include <string>

namespace vtkDP
{
/** Sets option `name` (its name or property) of `options` to `value` clamped to its range.
 *  Returns whether the value changed; an unknown name or a NaN leaves `options` as they were and
 *  says why in `error`. */
template <typename Options>
bool setOption(const dp::OptionTable<Options>& table, Options& options, const char* name,
               double value, std::string& error)
{
  try
  {
    const auto& option = table.find(name ? name : "");
    const double v = option.clamped(value, table.what());
    if (option.get(options) == v)
      return false;
    option.set(options, v);
    return true;
  }
  catch (const std::invalid_argument& e)
  {
    error = e.what();
    return false;
  }
}

/** The value of option `name`; 0 with `error` set when there is no such option. */
template <typename Options>
double getOption(const dp::OptionTable<Options>& table, const Options& options, const char* name,
                 std::string& error)
{
  try
  {
    return table.find(name ? name : "").get(options);
  }
  catch (const std::invalid_argument& e)
  {
    error = e.what();
    return 0;
  }
}
} // namespace vtkDP

#endif
