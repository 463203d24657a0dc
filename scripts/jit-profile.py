#!/usr/bin/env python3
"""Where llvmpipe's JIT-compiled kernels spend their time, instruction by instruction.

Mesa's release builds have no IR or assembly dump (GALLIVM_DEBUG is debug-only), and the
kernels' machine code lives in anonymous executable mappings, so perf alone cannot name it. This
script samples a running umbra process with `perf record`, maps each sample's instruction address
to the anonymous executable region that holds it (`/proc/PID/maps`), dumps the hottest regions
with gdb and disassembles them with objdump, each instruction annotated with its share of the
samples. A region is one compiled kernel variant (or several small ones); a kernel is recognised
by a float constant of its own (`--find 0.99999` prints the regions whose bytes hold that f32).

    umbra-bench shadows ... &                      # any long run
    python3 scripts/jit-profile.py --pid $! --seconds 20 --top 3 --out out/profile
    python3 scripts/jit-profile.py --pid $! --seconds 20 --find 0.99999 --out out/profile

Needs perf, gdb and objdump (binutils); run as root or with perf_event_paranoid ≤ 1.
"""
import argparse
import collections
import os
import struct
import subprocess
import sys


def anon_exec_regions(pid):
    regions = []
    with open(f"/proc/{pid}/maps") as f:
        for line in f:
            parts = line.split()
            lo, hi = (int(x, 16) for x in parts[0].split("-"))
            if "x" in parts[1] and (len(parts) < 6 or parts[5].startswith("[anon") or parts[5] == ""):
                regions.append((lo, hi))
    return regions


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--pid", type=int, required=True)
    ap.add_argument("--seconds", type=float, default=10.0)
    ap.add_argument("--top", type=int, default=3, help="regions to disassemble")
    ap.add_argument("--find", type=float, action="append", default=[],
                    help="also disassemble regions holding this f32 constant")
    ap.add_argument("--out", default="out/profile")
    ap.add_argument("--no-record", action="store_true", help="analyse the perf.data already in --out")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    data = os.path.join(args.out, "perf.data")
    if not args.no_record:
        subprocess.run(["perf", "record", "-q", "-F", "4000", "-p", str(args.pid), "-o", data, "--",
                        "sleep", str(args.seconds)], check=True)
    # Regions are read after the samples: kernels compiled during the run are mapped by then.
    regions = anon_exec_regions(args.pid)
    script = subprocess.run(["perf", "script", "-i", data, "-F", "ip,dso"], capture_output=True,
                            text=True, check=True).stdout
    per_ip = collections.Counter()
    total = 0
    elsewhere = collections.Counter()
    for line in script.splitlines():
        parts = line.split()
        if not parts:
            continue
        total += 1
        ip = int(parts[0], 16)
        dso = parts[1] if len(parts) > 1 else "?"
        # perf names memory without a file after the JIT map it looks for (/tmp/perf-PID.map).
        if "unknown" in dso or "anon" in dso or "/perf-" in dso:
            per_ip[ip] += 1
        else:
            elsewhere[dso] += 1
    per_region = collections.Counter()
    for ip, n in per_ip.items():
        for lo, hi in regions:
            if lo <= ip < hi:
                per_region[(lo, hi)] += n
                break
    print(f"{total} samples; JIT code {sum(per_ip.values())} ({100 * sum(per_ip.values()) / max(total, 1):.1f} %)")
    for dso, n in elsewhere.most_common(8):
        print(f"  {100 * n / total:5.1f} %  {dso}")
    ranked = per_region.most_common()
    for (lo, hi), n in ranked[:12]:
        print(f"  {100 * n / total:5.1f} %  region {lo:#x}-{hi:#x} ({(hi - lo) // 1024} KiB)")

    def dump(lo, hi):
        path = os.path.join(args.out, f"region-{lo:x}.bin")
        subprocess.run(["gdb", "-p", str(args.pid), "-batch", "-ex",
                        f"dump memory {path} {lo:#x} {hi:#x}"], capture_output=True, check=True)
        return path

    chosen = [r for r, _ in ranked[:args.top]]
    if args.find:
        needles = [struct.pack("<f", v) for v in args.find]
        for (lo, hi), _ in ranked:
            if (lo, hi) in chosen:
                continue
            with open(dump(lo, hi), "rb") as f:
                blob = f.read()
            if all(nd in blob for nd in needles):
                chosen.append((lo, hi))
    for lo, hi in chosen:
        path = dump(lo, hi)
        asm = subprocess.run(["objdump", "-D", "-b", "binary", "-m", "i386:x86-64", "--no-show-raw-insn",
                              f"--adjust-vma={lo:#x}", path], capture_output=True, text=True,
                             check=True).stdout
        n_region = per_region[(lo, hi)]
        out = os.path.join(args.out, f"region-{lo:x}.txt")
        with open(out, "w") as f:
            for line in asm.splitlines():
                head = line.strip().split(":", 1)[0]
                try:
                    ip = int(head, 16)
                except ValueError:
                    f.write(line + "\n")
                    continue
                n = per_ip.get(ip, 0)
                share = f"{100 * n / max(n_region, 1):5.2f}" if n else "     "
                f.write(f"{share} {line}\n")
        print(f"region {lo:#x}: {n_region} samples, annotated in {out}")


if __name__ == "__main__":
    sys.exit(main())
