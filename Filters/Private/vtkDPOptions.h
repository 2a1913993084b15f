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

/**
 * Defines a filter's generic option accessors, `Set<Family>(name, value)` and
 * `Get<Family>(name)`, over engine table `table` and the options the filter holds in
 * `this->Internal->Options`: a changed value marks the filter modified; an unknown name or a NaN
 * is reported as the filter's error. Used once per filter, in its .cxx, followed by a `;`.
 */
#define vtkDPOptionAccessorsMacro(Class, Family, table)                                            \
  void Class::Set##Family(const char* name, double value)                                          \
  {                                                                                                \
    std::string error;                                                                             \
    if (vtkDP::setOption(table, this->Internal->Options, name, value, error))                      \
      this->Modified();                                                                            \
    if (!error.empty())                                                                            \
      vtkErrorMacro(<< error);                                                                     \
  }                                                                                                \
  double Class::Get##Family(const char* name)                                                      \
  {                                                                                                \
    std::string error;                                                                             \
    const double v = vtkDP::getOption(table, this->Internal->Options, name, error);                \
    if (!error.empty())                                                                            \
      vtkErrorMacro(<< error);                                                                     \
    return v;                                                                                      \
  }                                                                                                \
  static_assert(true, "the macro is used as a statement")

#endif
