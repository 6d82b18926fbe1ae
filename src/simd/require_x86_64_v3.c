/*
 * The processor check of a windmeta binary built for x86-64-v3 (`.cargo/config.toml`): a
 * constructor that runs before any Rust code, including the runtime's start-up, which is compiled
 * for those instructions too. It is C, compiled by `build.rs` for the baseline x86-64, because
 * nothing compiled with the build's own flags can be trusted to run on a processor without them:
 * the compiler may use AVX, BMI or MOVBE encodings anywhere. Where an instruction set is missing it
 * says which, and exits with code 4 instead of dying of an illegal instruction.
 */
#include <cpuid.h>
#include <string.h>
#include <unistd.h>

static void say(const char *text) {
    ssize_t ignored = write(STDERR_FILENO, text, strlen(text));
    (void)ignored;
}

__attribute__((constructor)) static void windmeta_require_x86_64_v3(void) {
    unsigned int eax = 0, ebx = 0, ecx = 0, edx = 0;
    unsigned int ecx1 = 0, ebx7 = 0, ecx_ext = 0;
    if (__get_cpuid(1, &eax, &ebx, &ecx, &edx)) ecx1 = ecx;
    if (__get_cpuid_count(7, 0, &eax, &ebx, &ecx, &edx)) ebx7 = ebx;
    if (__get_cpuid(0x80000001, &eax, &ebx, &ecx, &edx)) ecx_ext = ecx;
    /* AVX needs the operating system to save the vector registers: OSXSAVE, then XCR0's SSE and AVX bits. */
    int os_saves_avx = 0;
    if (ecx1 & (1u << 27)) {
        unsigned int xcr0_low, xcr0_high;
        __asm__("xgetbv" : "=a"(xcr0_low), "=d"(xcr0_high) : "c"(0));
        os_saves_avx = (xcr0_low & 6u) == 6u;
    }
    struct { const char *name; int present; } required[] = {
        {"avx", (ecx1 & (1u << 28)) && os_saves_avx},
        {"avx2", (ebx7 & (1u << 5)) && os_saves_avx},
        {"fma", (ecx1 & (1u << 12)) && os_saves_avx},
        {"f16c", (ecx1 & (1u << 29)) != 0},
        {"bmi1", (ebx7 & (1u << 3)) != 0},
        {"bmi2", (ebx7 & (1u << 8)) != 0},
        {"lzcnt", (ecx_ext & (1u << 5)) != 0},
        {"movbe", (ecx1 & (1u << 22)) != 0},
        {"xsave", (ecx1 & (1u << 26)) != 0},
    };
    int missing = 0;
    for (unsigned int i = 0; i < sizeof required / sizeof required[0]; i++) {
        if (required[i].present) continue;
        say(missing++ ? ", " : "error: this processor lacks ");
        say(required[i].name);
    }
    if (!missing) return;
    say(". This windmeta is built for x86-64-v3 (AVX2, FMA, BMI1/2: Intel Haswell, AMD Zen and later);"
        " build one for this processor with RUSTFLAGS='-C target-cpu=native' cargo build --release\n");
    _exit(4);
}
