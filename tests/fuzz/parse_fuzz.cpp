// libFuzzer target: parse, compile and evaluate arbitrary text. Any crash, hang, sanitizer
// report or escaped exception is a bug: parse_field reports bad text as diagnostics, and
// evaluation turns bad values into NaN.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "zeroset/error.h"
#include "zeroset/expr/parse.h"
#include "zeroset/expr/polynomial.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  zeroset::ParseResult result = zeroset::parse_field(text);
  if (!result.ok()) {
    (void)result.format();
    return 0;
  }
  zeroset::Field& field = *result.field;
  for (const std::string& name : field.parameter_names()) field.set_parameter(name, 1.3);
  (void)field.expression_string();
  zeroset::Evaluator evaluator(field);
  const zeroset::Vec3 p(0.3, -0.7, 1.1);
  (void)evaluator.value(p);
  (void)evaluator.sample(p);
  double x[3] = {0.3, 0.0, -2.0}, y[3] = {-0.7, 0.0, 1.0}, z[3] = {1.1, 0.0, 0.5}, out[3];
  evaluator.values(x, y, z, out);
  // Expansion is bounded by Field::polynomial's own degree limit; 12 keeps the fuzzer fast.
  if (field.is_polynomial() && field.degree() <= 12) {
    const zeroset::Polynomial poly = field.polynomial();
    (void)poly.value(p);
    (void)poly.restrict_to_line(p, {0.6, 0.0, 0.8});
    (void)poly.to_string();
  }
  return 0;
}
