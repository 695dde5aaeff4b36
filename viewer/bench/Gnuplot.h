// Running a bench's gnuplot script: its PNGs appear whole or not at all.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace ml {

// A PNG the script writes: `set output VARIABLE` in the script, and a
// default `if (!exists('VARIABLE')) VARIABLE = 'FILE'` so it also runs alone.
struct GnuplotOutput {
    std::string variable;  // gnuplot identifier, e.g. "out_lights"
    std::string file;      // PNG name in the bench folder, e.g. "scaling_lights.png"
};

// The lines that give each output variable its default file name, to start a script with.
std::string gnuplotOutputDefaults(const std::vector<GnuplotOutput>& outputs);

// Writes `script` to dir/scriptName; if gnuplot is installed, runs it in
// `dir` with each variable set to a temporary name and renames the PNGs into
// place once it succeeds. Returns false, after printing a note, when gnuplot
// is missing (the CSVs hold the data); throws std::runtime_error when it
// fails on the script.
bool runGnuplotScript(const std::filesystem::path& dir, const std::string& scriptName, const std::string& script,
                      const std::vector<GnuplotOutput>& outputs);

// `s` as a gnuplot string literal: in single quotes, where a quote is
// written twice and nothing else is special.
std::string gnuplotQuoted(const std::string& s);

// `s` in single quotes for /bin/sh.
std::string shellQuoted(const std::string& s);

}  // namespace ml
