#include "CameraPath.h"

#include "Error.h"

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

namespace ml {

std::vector<Camera> loadCameraPath(const std::string& path) {
    std::ifstream in(path);
    if (!in) throw InputError(concat(path, ": cannot open the camera path"));
    std::vector<Camera> cameras;
    std::string line;
    int lineNo = 0;
    while (std::getline(in, line)) {
        ++lineNo;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        size_t first = line.find_first_not_of(" \t");
        if (first == std::string::npos || line[first] == '#') continue;
        if (lineNo == 1 && std::isalpha(static_cast<unsigned char>(line[first]))) continue;  // header
        const SourceLocation where{path, lineNo};
        std::vector<double> v;
        std::stringstream fields(line);
        std::string field;
        while (std::getline(fields, field, ',')) {
            const size_t b = field.find_first_not_of(" \t"), e = field.find_last_not_of(" \t");
            const std::string text = b == std::string::npos ? std::string() : field.substr(b, e - b + 1);
            char* end = nullptr;
            const double x = std::strtod(text.c_str(), &end);
            if (text.empty() || *end != '\0')
                throwInputError(where, concat("field ", v.size() + 1, " '", text, "' is not a number"));
            if (!std::isfinite(x)) throwInputError(where, concat("field ", v.size() + 1, " is not finite"));
            v.push_back(x);
        }
        if (v.size() != 10)
            throwInputError(where, concat(v.size(), " fields, expected 10: px,py,pz,tx,ty,tz,ux,uy,uz,fov"));
        Camera c;
        c.position = {v[0], v[1], v[2]};
        c.target = {v[3], v[4], v[5]};
        c.up = {v[6], v[7], v[8]};
        c.fovYDegrees = v[9];
        try {
            c.validate();
        } catch (const InputError& e) {
            throwInputError(where, e.what());
        }
        cameras.push_back(c);
    }
    if (cameras.empty()) throw InputError(concat(path, ": the camera path has no camera"));
    return cameras;
}

}  // namespace ml
