# util/color: the CIE colour matching functions, the D65 illuminant and the Smits
# (1999) basis spectra live in CSV files beside this file (as published, with
# their sources); they are compiled into C arrays at build time. Nothing
# generated is committed.
set(TB_COLOR_DIR ${CMAKE_CURRENT_LIST_DIR})
set(TB_COLOR_GEN_DIR ${PROJECT_BINARY_DIR}/generated/color)
set(TB_COLOR_TABLES_C ${TB_COLOR_GEN_DIR}/color_tables.c)
set(TB_COLOR_TABLES_H ${TB_COLOR_GEN_DIR}/color_tables.h)
set(TB_COLOR_CSVS
    ${TB_COLOR_DIR}/cie1931-2deg-5nm.csv
    ${TB_COLOR_DIR}/cie-d65-5nm.csv
    ${TB_COLOR_DIR}/smits1999-basis.csv)
add_custom_command(
  OUTPUT ${TB_COLOR_TABLES_C} ${TB_COLOR_TABLES_H}
  COMMAND ${CMAKE_COMMAND} -DOUT_C=${TB_COLOR_TABLES_C} -DOUT_H=${TB_COLOR_TABLES_H}
          "-DTABLES=cie1931=${TB_COLOR_DIR}/cie1931-2deg-5nm.csv|d65=${TB_COLOR_DIR}/cie-d65-5nm.csv|smits1999=${TB_COLOR_DIR}/smits1999-basis.csv"
          -P ${TB_COLOR_DIR}/gen_color_tables.cmake
  DEPENDS ${TB_COLOR_CSVS} ${TB_COLOR_DIR}/gen_color_tables.cmake
  COMMENT "Compiling the colour tables (CIE 1931 CMFs, D65, Smits 1999) from CSV"
  VERBATIM)
# The header is listed too so that it exists before any library source that
# includes it is compiled.
target_sources(testbed_obj PRIVATE ${TB_COLOR_TABLES_C} ${TB_COLOR_TABLES_H})
