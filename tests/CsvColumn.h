// Reading back one value of a CSV file a command wrote (probe, bench logs):
// the first line names the columns, the rest are data rows.
#pragma once

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace ml::test {

// The value in column `name` of data row `row` (0: the line after the
// header) of `file`. A missing file, row or column is a test failure naming
// what is missing, and reads as 0.
inline double csvColumn(const std::string& file, int row, const std::string& name) {
    auto split = [](const std::string& line) {
        std::vector<std::string> cells;
        std::stringstream in(line);
        std::string cell;
        while (std::getline(in, cell, ',')) cells.push_back(cell);
        return cells;
    };
    std::ifstream in(file);
    std::string header, line;
    if (!std::getline(in, header)) {
        ADD_FAILURE() << "cannot read " << file;
        return 0;
    }
    for (int i = 0; i <= row; ++i)
        if (!std::getline(in, line)) {
            ADD_FAILURE() << file << " has no data row " << row;
            return 0;
        }
    const std::vector<std::string> names = split(header), cells = split(line);
    for (size_t i = 0; i < names.size() && i < cells.size(); ++i)
        if (names[i] == name) return std::stod(cells[i]);
    ADD_FAILURE() << "no column " << name << " in row " << row << " of " << file;
    return 0;
}

}  // namespace ml::test
