# cmake -DSPV=in.spv -DOUT=out.inc -DNAME=c_identifier -P embed_spirv.cmake
# Writes the SPIR-V words of SPV as `static const uint32_t NAME[] = {...};`
# (host byte order, which is what vkCreateShaderModule reads).
file(READ "${SPV}" hex HEX)
string(LENGTH "${hex}" nhex)
math(EXPR rem "${nhex} % 8")
if(nhex EQUAL 0 OR NOT rem EQUAL 0)
  message(FATAL_ERROR "${SPV}: not a SPIR-V module (size is not a positive multiple of 4 bytes)")
endif()
string(SUBSTRING "${hex}" 0 8 magic)
if(NOT magic STREQUAL "03022307")
  message(FATAL_ERROR "${SPV}: bad SPIR-V magic ${magic} (expected little-endian 0x07230203)")
endif()
# Bytes are little-endian on every target we build for: word = b3 b2 b1 b0.
string(REGEX REPLACE "(..)(..)(..)(..)" "0x\\4\\3\\2\\1u," words "${hex}")
string(REGEX REPLACE "((0x........u,){8})" "\\1\n    " words "${words}")
file(WRITE "${OUT}.tmp"
  "/* Generated from ${SPV} by host/gpu/embed_spirv.cmake: do not edit. */\n"
  "static const uint32_t ${NAME}[] = {\n    ${words}\n};\n")
# Only touch OUT when it changed, so an unchanged module does not recompile the table.
file(COPY_FILE "${OUT}.tmp" "${OUT}" ONLY_IF_DIFFERENT)
file(REMOVE "${OUT}.tmp")
