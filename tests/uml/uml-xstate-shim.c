/* uml-xstate-shim.c - LD_PRELOAD shim for linux.uml (used by uml-run).
 *
 * UML before Linux 6.13 saves/restores the guest FPU state with
 * PTRACE_{GET,SET}REGSET(NT_X86_XSTATE) using a buffer of compile-time size.
 * On hosts whose XSAVE area is larger (AVX-512 + AMX: 11008 bytes) the host
 * kernel rejects the short SETREGSET with EFAULT and UML panics right after
 * starting init ("userspace - ptrace set fp regs failed, errno = 14").
 * This shim keeps a full-size shadow of every UML FPU buffer and performs
 * the real calls with the full size, so the complete host FPU state of each
 * guest thread is saved and restored.  It is a pass-through when UML's
 * buffer is already large enough.  (Forcing the old FXSAVE fallback instead
 * is NOT safe: guest glibc uses AVX-512 registers and crashed.) */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <sys/uio.h>
#include <sys/ptrace.h>
#include <linux/elf.h>

#define NSLOT 8192
static struct { void *key; unsigned char *buf; } slot[NSLOT];
static size_t xsize;
static long (*real)(int, pid_t, void *, void *);

static unsigned char *shadow(void *key, int create)
{
	size_t h = ((uintptr_t)key >> 4) % NSLOT;
	for (size_t i = 0; i < NSLOT; i++, h = (h + 1) % NSLOT) {
		if (slot[h].key == key)
			return slot[h].buf;
		if (!slot[h].key) {
			if (!create || !(slot[h].buf = calloc(1, xsize)))
				return NULL;
			slot[h].key = key;
			return slot[h].buf;
		}
	}
	return NULL;
}

long ptrace(enum __ptrace_request req, ...)
{
	va_list ap;
	va_start(ap, req);
	pid_t pid = va_arg(ap, pid_t);
	void *addr = va_arg(ap, void *);
	void *data = va_arg(ap, void *);
	va_end(ap);
	if (!real)
		real = (long (*)(int, pid_t, void *, void *))dlsym(RTLD_NEXT, "ptrace");
	if ((req != PTRACE_GETREGSET && req != PTRACE_SETREGSET) ||
	    (uintptr_t)addr != NT_X86_XSTATE)
		return real(req, pid, addr, data);

	struct iovec *iov = data, big;
	if (!xsize) {	/* learn the host's full XSAVE size */
		static unsigned char probe[1 << 16];
		big.iov_base = probe;
		big.iov_len = sizeof(probe);
		if (real(PTRACE_GETREGSET, pid, addr, &big) < 0)
			return -1;
		xsize = big.iov_len;
	}
	if (iov->iov_len >= xsize)
		return real(req, pid, addr, data);

	unsigned char *sh = shadow(iov->iov_base, 1);
	if (!sh) {
		errno = ENOMEM;
		return -1;
	}
	big.iov_base = sh;
	big.iov_len = xsize;
	if (req == PTRACE_GETREGSET) {
		if (real(req, pid, addr, &big) < 0)
			return -1;
		memcpy(iov->iov_base, sh, iov->iov_len);
		return 0;
	}
	memcpy(sh, iov->iov_base, iov->iov_len);
	return real(req, pid, addr, &big);
}
