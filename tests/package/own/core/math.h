// A header of the user's own project with the name of one of aarad's (core/math.h). aarad's headers include one
// another as "aarad/core/math.h", so this one, on the consumer's include path ahead of the package's, is never
// reached from them; before they did, it was, and nothing of aarad compiled.
#error "aarad's installed headers included the consumer's own core/math.h instead of their own"
