"""Whether a call releases the GIL, decided without timing thresholds.

The call runs in a worker thread while the switch interval is huge, so the interpreter never
takes the GIL from the worker by itself: the main thread can only run (and count) while the
worker is inside C++ with the GIL released. Holding the GIL gives exactly 0 counts, however
busy the machine; releasing it gives > 0 as long as the call lasts long enough for the OS to
schedule the main thread once (make it last a few hundred milliseconds).
"""
import sys
import time
import threading


def run_counting_main_thread(call):
    """Returns (call's result, how often the main thread ran while the call was in progress)."""
    done = []
    old = sys.getswitchinterval()
    sys.setswitchinterval(1000.0)
    try:
        worker = threading.Thread(target=lambda: done.append(call()))
        worker.start()
        counts = 0
        while worker.is_alive():
            counts += 1
            time.sleep(0)  # hands the GIL back, so a worker returning from C++ can take it
        worker.join()
    finally:
        sys.setswitchinterval(old)
    assert done, "the call raised in the worker thread"
    return done[0], counts
