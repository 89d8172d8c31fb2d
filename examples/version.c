/* Prints the version of the roadnn library it runs with. */
#include <stdio.h>

#include <roadnn/roadnn.h>

int main(void) {
  printf("%s\n", roadnn_version());
  return 0;
}
