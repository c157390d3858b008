/* This process as an AVX2 CPU without AVX-512 or AVX-VNNI (a Haswell's vector features), run
 * natively: loaded with LD_PRELOAD, it has Linux make the CPUID instruction fault
 * (arch_prctl ARCH_SET_CPUID, on CPUs with cpuid_fault in /proc/cpuinfo), answers each CPUID itself
 * with the real answer less those features, and goes on. Libraries that choose their kernels by
 * CPUID after it loads (onnxruntime's MLAS, numpy) choose the AVX2 ones, and the real CPU runs them
 * exactly as a Haswell would: integer saturation and FMA rounding are the instructions' own.
 * bench/tools/avx2_cpu.py builds and loads it; glibc chose its string functions before it loaded. */
#define _GNU_SOURCE
#include <asm/prctl.h>
#include <cpuid.h>
#include <signal.h>
#include <string.h>
#include <sys/syscall.h>
#include <ucontext.h>
#include <unistd.h>

#define BIT(n) (1u << (n))
/* leaf 7, subleaf 0: AVX-512 F, DQ, IFMA, PF, ER, CD, BW, VL; VBMI, VBMI2, VNNI, BITALG, VPOPCNTDQ;
 * 4VNNIW, 4FMAPS, VP2INTERSECT, AMX-BF16, FP16, AMX-TILE, AMX-INT8 */
#define LEAF7_EBX (BIT(16) | BIT(17) | BIT(21) | BIT(26) | BIT(27) | BIT(28) | BIT(30) | BIT(31))
#define LEAF7_ECX (BIT(1) | BIT(6) | BIT(11) | BIT(12) | BIT(14))
#define LEAF7_EDX (BIT(2) | BIT(3) | BIT(8) | BIT(22) | BIT(23) | BIT(24) | BIT(25))
/* leaf 7, subleaf 1: AVX-VNNI, AVX512-BF16, AVX-IFMA; AVX-VNNI-INT8, AVX-NE-CONVERT, AVX-VNNI-INT16 */
#define LEAF7_1_EAX (BIT(4) | BIT(5) | BIT(23))
#define LEAF7_1_EDX (BIT(4) | BIT(5) | BIT(10))

static long cpuid_faults(int faults) { return syscall(SYS_arch_prctl, ARCH_SET_CPUID, !faults); }

static void on_fault(int signal_number, siginfo_t *info, void *context) {
    greg_t *registers = ((ucontext_t *)context)->uc_mcontext.gregs;
    const unsigned char *instruction = (const unsigned char *)registers[REG_RIP];
    unsigned leaf = (unsigned)registers[REG_RAX], subleaf = (unsigned)registers[REG_RCX];
    unsigned a, b, c, d;
    (void)info;
    if (instruction[0] != 0x0f || instruction[1] != 0xa2) { /* a real fault: crash as without us */
        signal(signal_number, SIG_DFL);
        return;
    }
    cpuid_faults(0);
    __cpuid_count(leaf, subleaf, a, b, c, d);
    cpuid_faults(1);
    if (leaf == 7 && subleaf == 0) {
        b &= ~LEAF7_EBX;
        c &= ~LEAF7_ECX;
        d &= ~LEAF7_EDX;
    } else if (leaf == 7 && subleaf == 1) {
        a &= ~LEAF7_1_EAX;
        d &= ~LEAF7_1_EDX;
    }
    registers[REG_RAX] = a;
    registers[REG_RBX] = b;
    registers[REG_RCX] = c;
    registers[REG_RDX] = d;
    registers[REG_RIP] += 2; /* past CPUID (0F A2) */
}

__attribute__((constructor)) static void as_an_avx2_cpu(void) {
    struct sigaction action;
    memset(&action, 0, sizeof action);
    action.sa_sigaction = on_fault;
    action.sa_flags = SA_SIGINFO;
    sigaction(SIGSEGV, &action, 0);
    if (cpuid_faults(1) != 0) {
        static const char message[] = "avx2_cpu: this CPU cannot make CPUID fault (no cpuid_fault)\n";
        write(2, message, sizeof message - 1);
        _exit(3);
    }
}
