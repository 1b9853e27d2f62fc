"""stvm/frontend/waker.py: the VM thread wakes an event loop through a relay thread."""

from __future__ import annotations

import asyncio
import threading

from stvm.frontend.waker import LoopWaker


def test_wakes_from_another_thread_run_the_callback_in_the_loop_and_merge_while_pending():
    calls: list[str] = []

    async def main() -> None:
        loop = asyncio.get_running_loop()
        done = asyncio.Event()

        def callback() -> None:
            calls.append(threading.current_thread().name)
            if len(calls) == 2:
                done.set()
        waker = LoopWaker(loop, callback, name="test-waker")
        vm_thread = threading.Thread(target=lambda: [waker.wake() for _ in range(50)])
        vm_thread.start()
        vm_thread.join()
        await asyncio.sleep(0.05)
        first = len(calls)
        waker.wake()
        await asyncio.wait_for(done.wait(), 5)
        waker.close()
        assert not waker._thread.is_alive()
        assert 1 <= first < 50          # 50 wakes before the loop ran: merged
    asyncio.run(main())
    loop_thread = threading.current_thread().name
    assert calls and all(name == loop_thread for name in calls)


def test_a_wake_after_the_loop_closed_is_harmless():
    loop = asyncio.new_event_loop()
    waker = LoopWaker(loop, lambda: None)
    loop.close()
    waker.wake()
    waker._thread.join(2)
    assert not waker._thread.is_alive()   # the relay ended on the closed loop
    waker.close()
    waker.wake()
