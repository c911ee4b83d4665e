/* Every error message of the MID reader (docs/mid.md, section 11): a table of
 * malformed inputs, each with the exact message expected, written from the
 * specification by hand (line:column counted on the input). */
#include "tb_test.h"

#include <string.h>

#include "host/mid/mid_reader.h"

#define DATA TB_TESTS_DIR "/mid/data"

/* One malformed input: text (len bytes, or strlen when 0) and the message
 * after "scene.mid:". */
typedef struct error_case {
    const char *text;
    size_t len;
    const char *msg;
} error_case;

#define KINDS                                                                                              \
    "(expected sphere, cube, cylinder, cone, pyramid, prism, torus, polygons, conic, square_arch, "       \
    "round_arch, union, intersection, difference, material, point_light, spot_light, directional_light " \
    "or camera)"

static const error_case cases[] = {
    /* ---- lexical ---- */
    {"mid 1\nsphere { \0 }", 17, "2:10: error: NUL byte in the input"},
    {"mid 1\nsphere \"a\x80\" {}", 0, "2:10: error: invalid UTF-8 byte 0x80"},
    {"mid 1\nsphere \"\xC3(\" {}", 0, "2:9: error: invalid UTF-8 sequence starting with byte 0xc3"},
    {"mid 1\nsphere \"\xED\xA0\x80\" {}", 0, "2:9: error: invalid UTF-8 sequence starting with byte 0xed"},
    {"mid 1\nsphere \"\xE0\x80\x80\" {}", 0, "2:9: error: invalid UTF-8 sequence starting with byte 0xe0"},
    {"mid 1\n# caf\xC3\n", 0, "2:6: error: invalid UTF-8 sequence starting with byte 0xc3"},
    {"mid 1\nsphere \"abc", 0, "2:8: error: unterminated string (a string ends on the line it starts)"},
    {"mid 1\nsphere \"abc\n\" {}", 0, "2:8: error: unterminated string (a string ends on the line it starts)"},
    {"mid 1\nsphere \"a\tb\" {}", 0,
     "2:10: error: control character 0x09 in a string (write it as an escape such as \\n or \\u{9})"},
    {"mid 1\nsphere \"\\u{}\" {}", 0, "2:9: error: malformed escape: expected \\u{HEX} with 1 to 6 hex digits"},
    {"mid 1\nsphere \"\\u12\" {}", 0, "2:9: error: malformed escape: expected \\u{HEX} with 1 to 6 hex digits"},
    {"mid 1\nsphere \"\\u{1234567}\" {}", 0,
     "2:9: error: malformed escape: expected \\u{HEX} with 1 to 6 hex digits"},
    {"mid 1\nsphere \"\\u{d800}\" {}", 0,
     "2:9: error: \\u{d800} is not allowed (a Unicode scalar value from 1 to 10ffff, not a surrogate)"},
    {"mid 1\nsphere \"\\u{0}\" {}", 0,
     "2:9: error: \\u{0} is not allowed (a Unicode scalar value from 1 to 10ffff, not a surrogate)"},
    {"mid 1\nsphere \"\\u{110000}\" {}", 0,
     "2:9: error: \\u{110000} is not allowed (a Unicode scalar value from 1 to 10ffff, not a surrogate)"},
    {"mid 1\nsphere \"\\q\" {}", 0,
     "2:9: error: unknown escape '\\q' in a string (use \\\" \\\\ \\n \\t \\r or \\u{HEX})"},
    {"mid 1\nsphere \"\\\x01\" {}", 0,
     "2:9: error: unknown escape in a string (use \\\" \\\\ \\n \\t \\r or \\u{HEX})"},
    {"mid 1\nsphere { geometry = { r = 1.5.2 } }", 0, "2:27: error: malformed number '1.5.2'"},
    {"mid 1\nsphere { a = 3x }", 0, "2:14: error: malformed number '3x'"},
    {"mid 1\nsphere { a = 1e }", 0, "2:14: error: malformed number '1e'"},
    {"mid 1\nsphere { a = - }", 0, "2:14: error: malformed number '-'"},
    {"mid 1\nsphere { a = 1e999 }", 0, "2:14: error: number out of range '1e999' (beyond the largest double)"},
    {"mid 1\nsphere { a = -2e308 }", 0, "2:14: error: number out of range '-2e308' (beyond the largest double)"},
    {"mid 1\nsphere { a = @ }", 0, "2:14: error: unexpected character '@'"},
    {"\xEF\xBB\xBFmid 1\n", 0,
     "1:1: error: byte-order mark at the start of the file (MID files are UTF-8 without a BOM)"},
    {"mid 1\nsphere { a = \x01 }", 0, "2:14: error: unexpected byte 0x01 outside a string or comment"},
    {"mid 1\nsphere { a = \xC3\xA9 }", 0, "2:14: error: unexpected byte 0xc3 outside a string or comment"},

    /* ---- syntax ---- */
    {"mid 1\nsphere { a = [1 2", 0, "2:18: error: expected ']' to close the list opened at 2:14, found end of file"},
    {"mid 1\nsphere { a = f(1", 0, "2:17: error: expected ')' to close 'f(' opened at 2:14, found end of file"},
    {"mid 1\nsphere { a = [1 } }", 0,
     "2:17: error: expected a value or ']' to close the list opened at 2:14, found '}'"},
    {"mid 1\nsphere { a = [, 1] }", 0,
     "2:15: error: expected a value or ']' to close the list opened at 2:14, found ','"},
    {"mid 1\nsphere { a = [1, ] }", 0, "2:18: error: expected a value after ',', found ']'"},
    {"mid 1\nsphere { a = [1,, 2] }", 0, "2:17: error: expected a value after ',', found ','"},
    {"mid 1\nsphere { a = file(1) }", 0, "2:14: error: file() takes one string: file(\"path/to/data\")"},
    {"mid 1\nsphere { a = file(\"a\", \"b\") }", 0, "2:14: error: file() takes one string: file(\"path/to/data\")"},
    {"mid 1\nsphere { geometry = { a 1 } }", 0, "2:25: error: expected '=' after attribute name 'a', found number 1"},
    {"mid 1\nsphere { geometry = { a = 1", 0,
     "2:28: error: expected '}' to close the block opened at 2:21, found end of file"},
    {"mid 1\nsphere { geometry = { 1 } }", 0,
     "2:23: error: expected an attribute name or '}' to close the block opened at 2:21, found number 1"},
    {"mid 1\nsphere { a = }", 0, "2:14: error: expected a value for 'a', found '}'"},
    {"mid 1\nsphere { a = = }", 0, "2:14: error: expected a value for 'a', found '='"},
    {"mid 1\nsphre {}", 0, "2:1: error: unknown object kind 'sphre' " KINDS},
    {"mid 1.3\ndisk {}", 0,
     "2:1: error: unknown object kind 'disk' (the file is MID 1.3; this reader knows MID 1.1) " KINDS},
    {"mid 1\nsphere [", 0, "2:8: error: expected '{' to start the body of 'sphere', found '['"},
    {"mid 1\nsphere \"ball\" \"b\"", 0,
     "2:15: error: expected '{' to start the body of 'sphere', found string \"b\""},
    {"mid 1\nsphere {", 0, "2:9: error: expected '}' to close 'sphere' opened at 2:1, found end of file"},
    {"mid 1\nsphere { 1 }", 0,
     "2:10: error: expected an attribute name or '}' to close 'sphere' opened at 2:1, found number 1"},
    {"mid 1\nunion { 1 }", 0,
     "2:9: error: expected an attribute name, an object or '}' to close 'union' opened at 2:1, found number 1"},
    {"mid 1\nsphere { cube {} }", 0,
     "2:10: error: 'sphere' cannot contain objects (only union, intersection and difference can)"},
    {"mid 1\nsphere { foo {} }", 0, "2:14: error: expected '=' after attribute name 'foo', found '{'"},
    {"mid 1\nsphere { foo ] }", 0, "2:14: error: expected '=' after attribute name 'foo', found ']'"},
    {"mid 1\nunion { foo {} }", 0, "2:9: error: unknown object kind 'foo' " KINDS},
    {"mid 1\nunion { camera {} }", 0,
     "2:9: error: a camera cannot be part of a union (CSG nodes contain primitives and CSG nodes)"},
    {"mid 1\nsphere { a = 1 a = 2 }", 0, "2:16: error: duplicate attribute 'a' (first given at 2:10)"},
    {"mid 1\nsphere { geometry = { b = 1 b = 2 } }", 0,
     "2:29: error: duplicate attribute 'b' (first given at 2:23)"},
    {"", 0, "1:1: error: expected the version header 'mid 1' at the start of the file, found end of file"},
    {"sphere {}", 0, "1:1: error: expected the version header 'mid 1' at the start of the file, found 'sphere'"},
    {" mid 1\n", 0, "1:2: error: expected the version header 'mid 1' at the start of the file, found 'mid'"},
    {"mid\n1", 0,
     "2:1: error: expected a version number after 'mid' on the first line (e.g. 'mid 1'), found number 1"},
    {"mid 1e0", 0, "1:5: error: malformed version '1e0' (expected MAJOR or MAJOR.MINOR, e.g. 'mid 1')"},
    {"mid -1", 0, "1:5: error: malformed version '-1' (expected MAJOR or MAJOR.MINOR, e.g. 'mid 1')"},
    {"mid 1.", 0, "1:5: error: malformed version '1.' (expected MAJOR or MAJOR.MINOR, e.g. 'mid 1')"},
    {"mid 2", 0, "1:5: error: unsupported MID version 2 (this reader reads MID 1.x)"},
    {"mid 0.9", 0, "1:5: error: unsupported MID version 0.9 (this reader reads MID 1.x)"},
    {"mid 1\n{}", 0, "2:1: error: expected an object such as 'sphere { }', found '{'"},
    {"mid 1\nsphere {} }", 0, "2:11: error: expected an object such as 'sphere { }', found '}'"},

    /* ---- data files ---- */
    {"mid 1\nsphere { a = file(\"\") }", 0, "2:19: error: empty file name in file()"},
    {"mid 1\nsphere { a = file(\"x.fed\") }", 0,
     "2:19: error: data file 'x.fed' not found (looked for '" DATA "/x.fed')"},
    {"mid 1\nsphere { a = [file(\"checker.png\") file(\"sub/x.fed\")] }", 0,
     "2:40: error: data file 'sub/x.fed' not found (looked for '" DATA "/sub/x.fed')"},
    {"mid 1\nsphere { a = file(\"/\") }", 0, "2:19: error: data file '/' is not a regular file ('/')"},

    /* ---- values of known attributes ---- */
    {"mid 1\ncone { geometry = { top_radius = \"x\" } }", 0,
     "2:34: error: expected a number for 'top_radius', found a string"},
    {"mid 1\nmaterial \"m\" { exponent = 1e39 }", 0, "2:27: error: 'exponent' is out of range for a float, found 1e+39"},
    {"mid 1\npolygons { geometry = { vertices = [[1e39 0 0] [1 0 0] [0 1 0]] faces = [[0 1 2]] } }", 0,
     "2:37: error: 'vertices' is out of range for a float, found 1e+39"},
    {"mid 1\ntorus { geometry = { minor = -1 } }", 0, "2:30: error: 'minor' must be > 0, found -1"},
    {"mid 1\nmaterial \"m\" { diffuse = 2 }", 0, "2:26: error: 'diffuse' must be in [0, 1], found 2"},
    {"mid 1\nmaterial \"m\" { specular = [0 0.5 1.5] }", 0, "2:27: error: 'specular' must be in [0, 1], found 1.5"},
    {"mid 1\nmaterial \"m\" { emission = -1 }", 0, "2:27: error: 'emission' must be >= 0, found -1"},
    {"mid 1\nmaterial \"m\" { exponent = -1 }", 0, "2:27: error: 'exponent' must be >= 0, found -1"},
    {"mid 1\nmaterial \"m\" { ior = 0 }", 0, "2:22: error: 'ior' must be > 0, found 0"},
    {"mid 1\ncamera { fov = 180 }", 0, "2:16: error: 'fov' must be in (0, 180), found 180"},
    {"mid 1\nsquare_arch { geometry = { width = 2 } }", 0, "2:36: error: 'width' must be in (0, 2), found 2"},
    {"mid 1\ncone { geometry = { top_radius = -0.5 } }", 0, "2:34: error: 'top_radius' must be >= 0, found -0.5"},
    {"mid 1\nspot_light { cone_angle = 91 }", 0, "2:27: error: 'cone_angle' must be in (0, 90], found 91"},
    {"mid 1\ncylinder { geometry = { caps = 1 } }", 0, "2:32: error: expected true or false for 'caps', found 1"},
    {"mid 1\ncylinder { geometry = { caps = yes } }", 0,
     "2:32: error: expected true or false for 'caps', found 'yes'"},
    {"mid 1\ncamera { eye = [1 2] }", 0, "2:16: error: expected a 3-vector [x y z] for 'eye', found a list of 2 numbers"},
    {"mid 1\nprism { geometry = { sides = 3.5 } }", 0, "2:30: error: expected an integer for 'sides', found 3.5"},
    {"mid 1\nprism { geometry = { sides = 2 } }", 0,
     "2:30: error: 'sides' must be an integer from 3 to 1000000, found 2"},
    {"mid 1\nsphere { geometry = 1 }", 0, "2:21: error: expected a block { ... } for 'geometry', found 1"},
    {"mid 1\nsphere { rendering = [] }", 0, "2:22: error: expected a block { ... } for 'rendering', found an empty list"},
    {"mid 1\nmaterial \"m\" { diffuse_texture = \"x.png\" }", 0,
     "2:34: error: expected a file reference file(\"path\") for 'diffuse_texture', found a string"},

    /* ---- MID 1.1 material attributes: model, roughness, patterns, bump ---- */
    {"mid 1\nmaterial \"m\" { model = cook }", 0,
     "2:24: error: expected phong, blinn, lambert or ggx for 'model', found 'cook'"},
    {"mid 1\nmaterial \"m\" { model = \"ggx\" }", 0,
     "2:24: error: expected phong, blinn, lambert or ggx for 'model', found a string"},
    {"mid 1\nmaterial \"m\" { roughness = 1.5 }", 0,
     "2:28: error: 'roughness' must be in [0, 1], found 1.5"},
    {"mid 1\nmaterial \"m\" { roughness = -0.1 }", 0,
     "2:28: error: 'roughness' must be in [0, 1], found -0.1"},
    {"mid 1\nmaterial \"m\" { roughness = [0.1] }", 0,
     "2:28: error: expected a number for 'roughness', found a list of 1 number"},
    {"mid 1\nmaterial \"m\" { diffuse_pattern = 0.5 }", 0,
     "2:34: error: expected checker(...) or noise(...) for 'diffuse_pattern', found 0.5"},
    {"mid 1\nmaterial \"m\" { diffuse_pattern = stripes(1, 0, 1) }", 0,
     "2:34: error: unknown pattern 'stripes' for 'diffuse_pattern' (expected checker or noise)"},
    {"mid 1\nmaterial \"m\" { diffuse_pattern = checker(8, 0) }", 0,
     "2:34: error: checker takes a scale, two colours and an optional space: checker(scale, a, b [, uv|object])"},
    {"mid 1\nmaterial \"m\" { diffuse_pattern = checker(0, 0, 1) }", 0,
     "2:42: error: 'scale' must be > 0, found 0"},
    {"mid 1\nmaterial \"m\" { diffuse_pattern = checker([8 0], 0, 1) }", 0,
     "2:42: error: 'scale' must be > 0, found 0"},
    {"mid 1\nmaterial \"m\" { diffuse_pattern = checker([1 2 3], 0, 1) }", 0,
     "2:42: error: expected a number for 'scale', found a list of 3 numbers"},
    {"mid 1\nmaterial \"m\" { diffuse_pattern = noise([2 3], 4, 0, 1, object) }", 0,
     "2:40: error: a scale [su sv] applies to (u, v); object space takes one number"},
    {"mid 1\nmaterial \"m\" { diffuse_pattern = checker(8, 0, 2) }", 0,
     "2:48: error: 'diffuse_pattern' must be in [0, 1], found 2"},
    {"mid 1\nmaterial \"m\" { diffuse_pattern = checker(8, 0, [1 0]) }", 0,
     "2:48: error: expected a colour for 'diffuse_pattern' (a number, [r g b] or spectrum(...)), found a list of 2 numbers"},
    {"mid 1\nmaterial \"m\" { diffuse_pattern = checker(8, 0, 1, world) }", 0,
     "2:51: error: expected uv or object for the space of checker(), found 'world'"},
    {"mid 1\nmaterial \"m\" { specular_pattern = noise(4, 0, 0, 1) }", 0,
     "2:44: error: 'octaves' must be an integer from 1 to 16, found 0"},
    {"mid 1\nmaterial \"m\" { specular_pattern = noise(4, 2.5, 0, 1) }", 0,
     "2:44: error: expected an integer for 'octaves', found 2.5"},
    {"mid 1\nmaterial \"m\" { specular_pattern = noise(4, 3, 0) }", 0,
     "2:35: error: noise takes a scale, an octave count, two colours and an optional space: noise(scale, octaves, a, b [, uv|object])"},
    {"mid 1\nmaterial \"m\" { specular_pattern = noise(4, 3, 0, 1, 2) }", 0,
     "2:53: error: expected uv or object for the space of noise(), found 2"},
    {"mid 1\nmaterial \"m\" { specular_pattern = image(file(\"checker.png\"), 1) }", 0,
     "2:35: error: unknown pattern 'image' for 'specular_pattern' (expected checker or noise)"},
    {"mid 1\nmaterial \"m\" { bump = checker(8, 0, 1) }", 0,
     "2:23: error: unknown pattern 'checker' for 'bump' (expected noise or image)"},
    {"mid 1\nmaterial \"m\" { bump = noise(4, 3, 0, 1, uv) }", 0,
     "2:23: error: noise takes a scale, an octave count, a height and an optional space: noise(scale, octaves, height [, uv|object])"},
    {"mid 1\nmaterial \"m\" { bump = noise(4, 3, \"h\") }", 0,
     "2:35: error: expected a number for 'height', found a string"},
    {"mid 1\nmaterial \"m\" { bump = noise(-1, 3, 0.1) }", 0,
     "2:29: error: 'scale' must be > 0, found -1"},
    {"mid 1\nmaterial \"m\" { bump = image(\"checker.png\", 1) }", 0,
     "2:23: error: image takes a file and a height: image(file(\"heights.png\"), height)"},
    {"mid 1\nmaterial \"m\" { bump = image(file(\"checker.png\"), [1]) }", 0,
     "2:50: error: expected a number for 'height', found a list of 1 number"},
    {"mid 1\nmaterial \"m\" { bump = [1 2] }", 0,
     "2:23: error: expected noise(...) or image(...) for 'bump', found a list of 2 numbers"},

    /* ---- colours ---- */
    {"mid 1\nmaterial \"m\" { diffuse = spectrum(1) }", 0,
     "2:26: error: spectrum takes two lists or a file: spectrum([nm ...], [value ...]) or spectrum(file(\"...\"))"},
    {"mid 1\nmaterial \"m\" { diffuse = spectrum([400 500], [0.5]) }", 0,
     "2:26: error: spectrum has 2 wavelengths but 1 values"},
    {"mid 1\nmaterial \"m\" { diffuse = spectrum([400], [0.5]) }", 0,
     "2:26: error: a spectrum needs at least 2 samples, found 1"},
    {"mid 1\nmaterial \"m\" { diffuse = spectrum([0 500], [0.5 0.5]) }", 0,
     "2:35: error: spectrum wavelengths must be positive (nm), found 0"},
    {"mid 1\nmaterial \"m\" { diffuse = spectrum([500 400], [0.5 0.5]) }", 0,
     "2:35: error: spectrum wavelengths must increase, found 400 after 500"},
    {"mid 1\nmaterial \"m\" { diffuse = spectrum([400 500], [0.5 2]) }", 0,
     "2:46: error: 'diffuse' must be in [0, 1], found 2"},
    {"mid 1\nmaterial \"m\" { diffuse = \"red\" }", 0,
     "2:26: error: expected a colour for 'diffuse' (a number, [r g b] or spectrum(...)), found a string"},
    {"mid 1\nmaterial \"m\" { diffuse = [1 1] }", 0,
     "2:26: error: expected a colour for 'diffuse' (a number, [r g b] or spectrum(...)), found a list of 2 numbers"},

    /* ---- transforms ---- */
    {"mid 1\nsphere { transform = 1 }", 0,
     "2:22: error: expected a list of transform operations for 'transform' (e.g. [scale(2) translate([0 0 1])]), found 1"},
    {"mid 1\nsphere { transform = [1 x] }", 0,
     "2:23: error: expected a transform operation (translate, scale, rotate or matrix), found 1"},
    {"mid 1\nsphere { transform = [translate(1 2 3)] }", 0,
     "2:23: error: translate takes one 3-vector: translate([x y z])"},
    {"mid 1\nsphere { transform = [scale()] }", 0,
     "2:23: error: scale takes a number or a 3-vector: scale(s) or scale([x y z])"},
    {"mid 1\nsphere { transform = [scale([1 0 1])] }", 0,
     "2:23: error: scale factors must be non-zero (a zero scale is singular)"},
    {"mid 1\nsphere { transform = [rotate(45)] }", 0,
     "2:23: error: rotate takes an axis and an angle: rotate([x y z], degrees)"},
    {"mid 1\nsphere { transform = [rotate([0 0 0], 45)] }", 0, "2:23: error: the rotation axis must be non-zero"},
    {"mid 1\nsphere { transform = [matrix([1 2 3])] }", 0,
     "2:23: error: matrix takes one list of 16 numbers, row by row: matrix([m00 m01 ... m33])"},
    {"mid 1\nsphere { transform = [matrix([1 0 0 0 0 1 0 0 0 0 1 0 0 0 1 1])] }", 0,
     "2:23: error: the last row of a matrix must be 0 0 0 1 (MID transforms are affine)"},
    {"mid 1\nsphere { transform = [shear(1)] }", 0,
     "2:23: error: unknown transform operation 'shear' (expected translate, scale, rotate or matrix)"},
    {"mid 1\nsphere { transform = [scale(1e200) scale(1e200)] }", 0,
     "2:22: error: the composed transform overflows (its entries are not finite)"},
    {"mid 1\nsphere { transform = [translate([0 0 1]) matrix([1 0 0 0 0 1 0 0 0 0 0 0 0 0 0 1])] }", 0,
     "2:42: error: matrix is singular or ill-conditioned (reciprocal condition number below 1e-12)"},
    {"mid 1\nsphere { transform = [scale([1 1 1e-13])] }", 0,
     "2:23: error: scale is singular or ill-conditioned (reciprocal condition number below 1e-12)"},
    {"mid 1\nunion { transform = [scale(1e200)] sphere { transform = [scale(1e200)] } }", 0,
     "2:36: error: the transform overflows when composed with its parents' transforms"},

    /* ---- geometry ---- */
    {"mid 1\npolygons { geometry = { vertices = 1 faces = [[0 1 2]] } }", 0,
     "2:36: error: expected a list of 3-vectors for 'vertices', e.g. [[0 0 0] [1 0 0] [0 1 0]], found 1"},
    {"mid 1\npolygons { geometry = { vertices = [[0 0 0] [1 0] [0 1 0]] faces = [[0 1 2]] } }", 0,
     "2:45: error: 'vertices' element 1: expected a 3-vector [x y z], found a list of 2 numbers"},
    {"mid 1\npolygons { geometry = { vertices = [[0 0 0] [1 0 0] [0 1 0]] faces = [] } }", 0,
     "2:70: error: 'faces' needs at least one face"},
    {"mid 1\npolygons { geometry = { vertices = [[0 0 0] [1 0 0] [0 1 0]] faces = 1 } }", 0,
     "2:70: error: expected a list of faces for 'faces', e.g. [[0 1 2] [0 2 3]], found 1"},
    {"mid 1\npolygons { geometry = { vertices = [[0 0 0] [1 0 0] [0 1 0]] faces = [[0 1 2] \"x\"] } }", 0,
     "2:79: error: face 1: expected a list of vertex indices, found a string"},
    {"mid 1\npolygons { geometry = { vertices = [[0 0 0] [1 0 0] [0 1 0]] faces = [[0 1]] } }", 0,
     "2:71: error: face 0 has 2 vertices (a face needs at least 3)"},
    {"mid 1\npolygons { geometry = { vertices = [[0 0 0] [1 0 0] [0 1 0]] faces = [[0 1 3]] } }", 0,
     "2:71: error: face 0: vertex index 3 is not an integer from 0 to 2"},
    {"mid 1\npolygons { geometry = { vertices = [[0 0 0] [1 0 0] [0 1 0]] faces = [[0 1 0.5]] } }", 0,
     "2:71: error: face 0: vertex index 0.5 is not an integer from 0 to 2"},
    {"mid 1\npolygons { geometry = { mesh = file(\"checker.png\") vertices = [[0 0 0]] } }", 0,
     "2:63: error: polygons takes either a 'mesh' file or inline 'vertices' and 'faces', not both"},
    {"mid 1\npolygons { geometry = { mesh = \"m.fed\" } }", 0,
     "2:32: error: expected a file reference file(\"path\") for 'mesh', found a string"},
    {"mid 1\npolygons { geometry = { vertices = [[0 0 0] [1 0 0] [0 1 0]] } }", 0,
     "2:23: error: polygons needs 'vertices' and 'faces', or a 'mesh' file"},
    {"mid 1\npolygons { geometry = { vertices = [[0 0 0] [1 0 0]] faces = [[0 1 2]] } }", 0,
     "2:36: error: 'vertices' needs at least 3 vertices, found 2"},
    {"mid 1\npolygons { geometry = { vertices = [[0 0 0] [1 0 0] [0 1 0]] faces = [[0 1 2]] normals = [[0 0 1]] } }",
     0, "2:90: error: 'normals' has 1 entries for 3 vertices (one per vertex)"},
    {"mid 1\npolygons { geometry = { vertices = [[0 0 0] [1 0 0] [0 1 0]] faces = [[0 1 2]] uvs = [[0 0]] } }", 0,
     "2:86: error: 'uvs' has 1 entries for 3 vertices (one per vertex)"},
    {"mid 1\npolygons {}", 0,
     "2:1: error: polygons needs 'geometry = { vertices = [...] faces = [...] }' or 'geometry = { mesh = "
     "file(\"...\") }'"},
    {"mid 1\nconic { geometry = { z_range = [1 -1] } }", 0,
     "2:20: error: 'z_range' must be increasing [z0 z1], found [1 -1]"},
    {"mid 1\nconic { geometry = { coefficients = [1e308 1e308 0] } }", 0,
     "2:20: error: conic radius overflows at z = -1"},
    {"mid 1\nconic { geometry = { coefficients = [-1 0 0] } }", 0,
     "2:20: error: conic radius is imaginary: c0 + c1 z + c2 z^2 = -1 < 0 at z = -1"},
    {"mid 1\nconic { geometry = { coefficients = [-1 0 1] z_range = [-2 2] } }", 0,
     "2:20: error: conic radius is imaginary: c0 + c1 z + c2 z^2 = -1 < 0 at z = 0"},
    {"mid 1\nconic { geometry = { coefficients = [0 0 0] } }", 0,
     "2:20: error: conic radius is zero on the whole z_range"},
    {"mid 1\nprism { geometry = { profile = [[0 0] [1 0]] } }", 0,
     "2:32: error: 'profile' needs at least 3 points, found 2"},
    {"mid 1\nprism { geometry = { profile = [[0 0] [1 0] [2 0]] } }", 0, "2:32: error: 'profile' encloses no area"},
    {"mid 1\nprism { geometry = { sides = 4 profile = [[0 0] [1 0] [0 1]] } }", 0,
     "2:22: error: prism takes 'sides' or 'profile', not both"},
    {"mid 1\ntorus { geometry = { minor = 2 } }", 0,
     "2:20: error: torus 'minor' (2) must be less than 'major' (1)"},
    {"mid 1\nround_arch { geometry = { width = 1.5 height = 0.5 } }", 0,
     "2:25: error: round arch 'height' (0.5) must be at least half the 'width' (1.5)"},

    /* ---- materials, CSG, lights, camera ---- */
    {"mid 1\nsphere { rendering = { material = 1 } }", 0,
     "2:35: error: expected a material name string for 'material', found 1"},
    {"mid 1\nsphere { rendering = { material = \"red\" } }", 0,
     "2:35: error: unknown material 'red' (materials must be defined before use)"},
    {"mid 1\nsphere { rendering = { material = \"red\" } }\nmaterial \"red\" {}", 0,
     "2:35: error: unknown material 'red' (materials must be defined before use)"},
    {"mid 1\nmaterial \"a\" { material = \"a\" }", 0,
     "2:27: error: unknown material 'a' (materials must be defined before use)"},
    {"mid 1\ndifference { sphere {} }", 0, "2:1: error: difference needs at least two child objects, found 1"},
    {"mid 1\nunion {}", 0, "2:1: error: union needs at least one child object"},
    {"mid 1\nunion { intersection {} }", 0, "2:9: error: intersection needs at least one child object"},
    {"mid 1\nspot_light { direction = [0 0 0] }", 0, "2:26: error: 'direction' must be non-zero"},
    {"mid 1\nspot_light { cone_angle = 10 cone_delta = 20 }", 0,
     "2:43: error: 'cone_delta' (20) must not exceed 'cone_angle' (10)"},
    {"mid 1\ncamera { resolution = [1 2 3] }", 0,
     "2:23: error: expected 2 integers [width height] for 'resolution', found a list of 3 numbers"},
    {"mid 1\ncamera { resolution = [0 5] }", 0,
     "2:23: error: 'resolution' must be an integer from 1 to 65536, found 0"},
    {"mid 1\ncamera { film = [0 24] }", 0, "2:17: error: 'film' sizes must be > 0, found [0 24]"},
    {"mid 1\ncamera { fov = 40 focal_length = 50 }", 0, "2:34: error: give either 'fov' or 'focal_length', not both"},
    {"mid 1\ncamera { eye = [0 0 -1] }", 0, "2:1: error: camera 'eye' and 'look_at' must differ"},
    {"mid 1\ncamera { up = [0 0 1] }", 0,
     "2:1: error: camera 'up' must be non-zero and not parallel to the view direction"},
    {"mid 1\ncamera { up = [0 0 0] }", 0,
     "2:1: error: camera 'up' must be non-zero and not parallel to the view direction"},
    {"mid 1\ncamera { eye = [-1e308 0 0] look_at = [1e308 0 0] }", 0,
     "2:1: error: camera 'look_at' is too far from 'eye'"},
    {"mid 1\nmaterial {}", 0, "2:1: error: a material needs a name: material \"NAME\" { ... }"},
    {"mid 1\nmaterial \"m\" {}\nmaterial \"m\" {}", 0, "3:1: error: material 'm' is already defined at 2:1"},
    {"mid 1\ncamera {}\ncamera {}", 0, "3:1: error: a scene has one camera; another was defined at 2:1"},
};

/* Reads `len` bytes of MID text to the end; the status of the first failure. */
static tb_status read_text(const char *text, size_t len)
{
    FILE *fp = len ? fmemopen((void *)text, len, "rb") : fopen("/dev/null", "rb");
    assert_non_null(fp);
    tb_mid_reader *r;
    tb_status st = tb_mid_reader_open_stream(&r, fp, "scene.mid", DATA);
    assert_int_equal(st, TB_OK);
    tb_mid_item it;
    int guard = 0;
    while (!(st = tb_mid_reader_next(r, &it)) && it.type != TB_MID_ITEM_END)
        assert_true(++guard < 1000);
    tb_mid_reader_close(r);
    fclose(fp);
    return st;
}

static void test_error_table(void **state)
{
    (void)state;
    int failures = 0;
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        const error_case *c = &cases[i];
        size_t len = c->len ? c->len : strlen(c->text);
        tb_clear_error();
        tb_status st = read_text(c->text, len);
        char expected[1024];
        snprintf(expected, sizeof expected, "scene.mid:%s", c->msg);
        if (st != TB_ERR_FORMAT || strcmp(tb_last_error(), expected) != 0) {
            print_message("case %zu: input %.60s\n  status %d\n  got      %s\n  expected %s\n", i, c->text,
                          (int)st, tb_last_error(), expected);
            failures++;
        }
    }
    assert_int_equal(failures, 0);
}

/* A text of `n` bytes from a prefix, a repeated filler and a suffix (malloc'd). */
static char *build(const char *prefix, char fill, size_t n, const char *suffix, size_t *len)
{
    size_t a = strlen(prefix), b = strlen(suffix);
    char *s = malloc(a + n + b + 1);
    assert_non_null(s);
    memcpy(s, prefix, a);
    memset(s + a, fill, n);
    memcpy(s + a + n, suffix, b + 1);
    *len = a + n + b;
    return s;
}

static void expect(const char *text, size_t len, const char *msg)
{
    tb_status st = read_text(text, len);
    assert_int_equal(st, TB_ERR_FORMAT);
    char expected[1024];
    snprintf(expected, sizeof expected, "scene.mid:%s", msg);
    assert_string_equal(tb_last_error(), expected);
}

/* Limits: tokens of 65536 bytes, 65 levels of nesting, repeats among many attributes. */
static void test_limits(void **state)
{
    (void)state;
    size_t len;
    /* A maximal string and identifier are fine, one byte more is not. */
    char *s = build("mid 1\nsphere { a = \"", 'x', 65535, "\" }", &len);
    assert_int_equal(read_text(s, len), TB_OK);
    free(s);
    s = build("mid 1\nsphere { a = \"", 'x', 65536, "\" }", &len);
    expect(s, len, "2:14: error: string longer than 65535 bytes");
    free(s);
    s = build("mid 1\nsphere { a = \"", 'x', 65533, "\xC3\xA9\" }", &len);
    assert_int_equal(read_text(s, len), TB_OK);
    free(s);
    s = build("mid 1\nsphere { a = \"", 'x', 65534, "\xC3\xA9\" }", &len);
    expect(s, len, "2:14: error: string longer than 65535 bytes");
    free(s);
    s = build("mid 1\nsphere { a = \"", 'x', 65534, "\\n\" }", &len);
    assert_int_equal(read_text(s, len), TB_OK);
    free(s);
    s = build("mid 1\nsphere { a = \"", 'x', 65535, "\\n\" }", &len);
    expect(s, len, "2:14: error: string longer than 65535 bytes");
    free(s);
    s = build("mid 1\nsphere { a", 'b', 65534, " = 1 }", &len);
    assert_int_equal(read_text(s, len), TB_OK);
    free(s);
    s = build("mid 1\nsphere { a", 'b', 65535, " = 1 }", &len);
    expect(s, len, "2:10: error: identifier longer than 65535 bytes");
    free(s);
    s = build("mid 1\nsphere { a = 1", '0', 65534, " }", &len);
    assert_int_equal(read_text(s, len), TB_ERR_FORMAT); /* 1e65534: fine length, out of range */
    assert_non_null(strstr(tb_last_error(), "number out of range"));
    free(s);
    s = build("mid 1\nsphere { a = 0.", '0', 65534, "1 }", &len);
    expect(s, len, "2:14: error: number longer than 65535 bytes");
    free(s);

    /* Lists: the object body is level 1, so 63 brackets fit and 64 do not. */
    s = build("mid 1\nsphere { a = ", '[', 63, "", &len);
    char *t = malloc(len + 64 + 4);
    memcpy(t, s, len);
    memset(t + len, ']', 63);
    memcpy(t + len + 63, " }", 3);
    assert_int_equal(read_text(t, len + 65), TB_OK);
    free(t);
    free(s);
    s = build("mid 1\nsphere { a = ", '[', 64, "", &len);
    expect(s, len, "2:77: error: nesting deeper than 64 levels");
    free(s);

    /* CSG: 64 nested unions are fine, the 65th object is one level too deep. */
    char buf[4096];
    for (int depth = 64; depth <= 65; depth++) {
        size_t n = (size_t)snprintf(buf, sizeof buf, "mid 1\n");
        for (int i = 0; i < depth - 1; i++)
            n += (size_t)snprintf(buf + n, sizeof buf - n, "union {\n");
        n += (size_t)snprintf(buf + n, sizeof buf - n, "sphere {}\n");
        for (int i = 0; i < depth - 1; i++)
            n += (size_t)snprintf(buf + n, sizeof buf - n, "}\n");
        if (depth == 64)
            assert_int_equal(read_text(buf, n), TB_OK);
        else
            expect(buf, n, "66:8: error: nesting deeper than 64 levels");
    }

    /* A repeat among more than 16 attributes (the sorted path). */
    size_t n = (size_t)snprintf(buf, sizeof buf, "mid 1\nsphere {\n");
    for (int i = 0; i < 20; i++)
        n += (size_t)snprintf(buf + n, sizeof buf - n, "a%d = %d\n", i % 18, i);
    n += (size_t)snprintf(buf + n, sizeof buf - n, "}\n");
    expect(buf, n, "21:1: error: duplicate attribute 'a0' (first given at 3:1)");
}

/* After an error every call gives it again; files that cannot be opened are I/O errors. */
static void test_sticky_error_and_io(void **state)
{
    (void)state;
    const char *text = "mid 1\nsphere {}\nsphere { a = }\nsphere {}\n";
    FILE *fp = fmemopen((void *)text, strlen(text), "rb");
    tb_mid_reader *r;
    assert_int_equal(tb_mid_reader_open_stream(&r, fp, "s.mid", NULL), TB_OK);
    tb_mid_item it;
    assert_int_equal(tb_mid_reader_next(r, &it), TB_OK);
    assert_int_equal(it.type, TB_MID_ITEM_OBJECT);
    assert_int_equal(tb_mid_reader_next(r, &it), TB_ERR_FORMAT);
    assert_string_equal(tb_last_error(), "s.mid:3:14: error: expected a value for 'a', found '}'");
    tb_clear_error();
    assert_int_equal(tb_mid_reader_next(r, &it), TB_ERR_FORMAT);
    assert_string_equal(tb_last_error(), "s.mid:3:14: error: expected a value for 'a', found '}'");
    assert_int_equal(it.type, TB_MID_ITEM_END);
    tb_mid_reader_close(r);
    fclose(fp);

    assert_int_equal(tb_mid_reader_open(&r, "/nonexistent-folder/scene.mid"), TB_ERR_IO);
    assert_null(r);
    assert_string_equal(tb_last_error(), "/nonexistent-folder/scene.mid: cannot open: No such file or directory");
    assert_int_equal(tb_mid_reader_open(&r, DATA), TB_ERR_IO);
    assert_string_equal(tb_last_error(), DATA ": is a folder, not a MID file");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_error_table),
        cmocka_unit_test(test_limits),
        cmocka_unit_test(test_sticky_error_and_io),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
