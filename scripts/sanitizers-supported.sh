#!/bin/sh
# Exit 0 when the compiler ($1) can build and run an ASan+UBSan program.
cc=${1:-cc}
d=$(mktemp -d) || exit 1
trap 'rm -rf "$d"' EXIT
printf 'int main(void){return 0;}\n' > "$d/t.c"
"$cc" -fsanitize=address,undefined "$d/t.c" -o "$d/t" 2>/dev/null && "$d/t"
