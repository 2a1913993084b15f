// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file OptionCode.h
 * @brief Writes what other files restate of an option table (OptionTable.h) from the table: a VTK
 *        class's named accessors, ParaView's properties, the documentation's Markdown table.
 *        An option is written once, as a row of its table; these forms follow from it.
 *
 * The forms live in the files that need them, between two marker lines: a line holding
 * `BEGIN generated options: TABLE` (optionally followed by `except NAME,NAME`, properties left
 * out) and a line holding `END generated options`. What is written between them depends on the
 * file's extension: `.h` the accessors (each a thin call of the class's generic accessor,
 * `Set<Family>(name, value)`), `.xml` the ServerManager properties, `.md` the table.
 * `dynamicpoints --option-code write ROOT` rewrites the product's regions, `check` lists those
 * out of date (a test runs it). Limits: the accessors' enum types (a choice's named values) and
 * the panel's property groups are written by hand beside the regions.
 */
#pragma once

#include "dp/io/OptionTable.h"

#include <functional>
#include <string>
#include <vector>

namespace dp
{

/** Which of a table's rows a region holds: those with a property, less `except`. */
std::vector<std::size_t> presentedRows(const OptionCodeTable& table,
                                       const std::vector<std::string>& except);

/** A VTK class's named accessors of those rows (clang-format left off around them). */
std::string vtkAccessors(const OptionCodeTable& table, const std::vector<std::string>& except);

/** ParaView ServerManager XML properties of those rows, indented for a proxy's body. */
std::string paraviewProperties(const OptionCodeTable& table,
                               const std::vector<std::string>& except);

/** What a region's BEGIN line asks for: its table's name and the properties left out. */
struct OptionRegion
{
  std::string table;
  std::vector<std::string> except;
};

/** `text` with each region's lines replaced by `generate(region)`; `source` names the text in
 *  errors (std::invalid_argument: a BEGIN without its END, or an END without a BEGIN). */
std::string rewriteOptionRegions(const std::string& text, const std::string& source,
                                 const std::function<std::string(const OptionRegion&)>& generate);

} // namespace dp
