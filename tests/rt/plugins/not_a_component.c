/* A shared library that is not a truecut component (no entry points). */
int not_a_component_answer(void) {
  return 42;
}
