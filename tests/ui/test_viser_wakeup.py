"""viser's message buffer written from other threads while its loop waits on it, as our
refresher does: with the mend installed (frontend/viser_wakeup.py) the buffer's event is
set only in its own loop, no writer fails and the loop still wakes for the last message.
(The race it mends, "deque mutated during iteration", was seen under the ten-browser
benchmark; it is too rare to provoke here on purpose.)"""

from __future__ import annotations

import asyncio
import threading

from viser._messages import RemoveNotificationMessage
from viser.infra._async_message_buffer import AsyncMessageBuffer

from frontend import viser_wakeup

WRITERS = 4
MESSAGES = 5_000
CONSUMERS = 8


def test_writers_in_other_threads_wake_the_loop_and_break_nothing() -> None:
    viser_wakeup.install()
    loop = asyncio.new_event_loop()
    buffer = AsyncMessageBuffer(event_loop=loop, persistent_messages=False)
    assert isinstance(buffer.message_event, viser_wakeup.LoopEvent)
    failures: list[BaseException] = []
    woken = 0

    async def consume() -> None:
        nonlocal woken
        while buffer.message_counter < WRITERS * MESSAGES:
            await buffer.message_event.wait()
            buffer.message_event.clear()
            woken += 1

    def write() -> None:
        try:
            for index in range(MESSAGES):
                buffer.push(RemoveNotificationMessage(uuid=f"{threading.get_ident()}-{index}"))
        except BaseException as failure:  # what the test looks for
            failures.append(failure)

    async def consumers() -> None:  # viser waits in one task per connection
        await asyncio.gather(*(consume() for _ in range(CONSUMERS)))

    consumer = threading.Thread(target=lambda: loop.run_until_complete(consumers()))
    consumer.start()
    writers = [threading.Thread(target=write) for _ in range(WRITERS)]
    for writer in writers:
        writer.start()
    for writer in writers:
        writer.join()
    consumer.join(timeout=30)
    loop.close()
    assert not consumer.is_alive(), "the loop missed the last message"
    assert failures == []
    assert woken >= 1
