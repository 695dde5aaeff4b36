#include "Gnuplot.h"

#include "core/Error.h"
#include "core/io/AtomicFile.h"

#include <cstdio>
#include <cstdlib>
#include <memory>
#include <stdexcept>

namespace ml {

std::string gnuplotOutputDefaults(const std::vector<GnuplotOutput>& outputs) {
    std::string s;
    for (const GnuplotOutput& o : outputs)
        s += concat("if (!exists('", o.variable, "')) ", o.variable, " = '", o.file, "'\n");
    return s;
}

std::string gnuplotQuoted(const std::string& s) {
    std::string out = "'";
    for (char c : s) out += c == '\'' ? std::string("''") : std::string(1, c);
    return out + "'";
}

std::string shellQuoted(const std::string& s) {
    std::string out = "'";
    for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return out + "'";
}

bool runGnuplotScript(const std::filesystem::path& dir, const std::string& scriptName, const std::string& script,
                      const std::vector<GnuplotOutput>& outputs) {
    writeTextFileAtomically((dir / scriptName).string(), script);
    if (std::system("command -v gnuplot > /dev/null 2>&1") != 0) {
        std::printf("note: gnuplot not found (Debian: apt-get install gnuplot-nox); plots skipped, "
                    "CSVs and %s written\n",
                    (dir / scriptName).string().c_str());
        return false;
    }
    std::vector<std::unique_ptr<AtomicOutput>> pngs;
    std::string assignments;
    for (const GnuplotOutput& o : outputs) {
        pngs.push_back(std::make_unique<AtomicOutput>((dir / o.file).string()));
        // Temporary names are ".NAME.tmp-PID-N": nothing to escape.
        assignments += concat(o.variable, "='", pngs.back()->path().filename().string(), "';");
    }
    const std::string command = concat("cd ", shellQuoted(dir.string()), " && gnuplot -e \"", assignments, "\" ",
                                       shellQuoted(scriptName));
    if (std::system(command.c_str()) != 0)
        throw std::runtime_error(concat("gnuplot failed on ", (dir / scriptName).string()));
    for (auto& png : pngs) png->commit();
    return true;
}

}  // namespace ml
