#!/usr/bin/python3
"""Loads the cores the way the session benchmark's peers do on average, without a session:
the control for tools/app_bench_session.sh (are the app's slow frames the session's work, or
any competitor for the 2 cores?).

usage: cpu_load.py PROCESSES SHARE SECONDS -- each process busy SHARE of every 100 ms."""
import multiprocessing
import sys
import time


def duty(share, seconds):
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        start = time.monotonic()
        while time.monotonic() - start < 0.1 * share:
            pass
        time.sleep(0.1 * (1 - share))


if __name__ == "__main__":
    processes, share, seconds = int(sys.argv[1]), float(sys.argv[2]), float(sys.argv[3])
    workers = [multiprocessing.Process(target=duty, args=(share, seconds)) for _ in range(processes)]
    for w in workers:
        w.start()
    for w in workers:
        w.join()
