# cmake -DIN=FILE -DOUT=FILE.inc -P EmbedText.cmake: FILE as a C++ raw string
# literal, so a shipped text file (a .hal wiring) is compiled into a program.
file(READ "${IN}" content)
string(FIND "${content}" ")truecut_embed\"" clash)
if(NOT clash EQUAL -1)
  message(FATAL_ERROR "${IN} contains the raw-string delimiter")
endif()
file(WRITE "${OUT}.tmp" "R\"truecut_embed(${content})truecut_embed\"\n")
file(RENAME "${OUT}.tmp" "${OUT}")
