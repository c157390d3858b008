from typing import List, Tuple

import pytest

from speech_event.adapters.executors import ClockExecutor
from speech_event.adapters.fake_clock import FakeClock
from speech_event.adapters.memory_bus import InMemoryBus
from speech_event.interfaces.periodic import Periodic
from speech_event.messages import String
from speech_event.ports import PublisherStatus


def test_timers_fire_in_time_order_and_ties_in_the_order_they_were_set() -> None:
    clock = FakeClock()
    fired: List[str] = []
    clock.call_at(2.0, lambda: fired.append("b"))
    clock.call_at(1.0, lambda: fired.append("a"))
    clock.call_at(2.0, lambda: fired.append("c"))
    cancelled = clock.call_at(1.5, lambda: fired.append("never"))
    cancelled.cancel()
    clock.advance_to(1.99)
    assert fired == ["a"]
    clock.advance(0.01)
    assert fired == ["a", "b", "c"]
    assert clock.now() == 2.0


def test_a_timer_set_while_firing_fires_in_the_same_advance_if_due() -> None:
    clock = FakeClock()
    seen: List[float] = []

    def set_another() -> None:
        clock.call_at(1.5, lambda: seen.append(clock.now()))

    clock.call_at(1.0, set_another)
    clock.advance_to(3.0)
    assert seen == [1.5]


def test_the_fake_clock_cannot_go_back() -> None:
    clock = FakeClock(5.0)
    with pytest.raises(ValueError) as error:
        clock.advance_to(4.0)
    assert str(error.value) == "the clock cannot go back from 5.0 to 4.0"


def test_periodic_fires_at_multiples_of_the_period_from_its_start() -> None:
    clock = FakeClock(1.0)
    times: List[float] = []
    periodic = Periodic(clock, 0.5, lambda: times.append(clock.now()))
    clock.advance_to(3.0)
    periodic.cancel()
    clock.advance_to(10.0)
    assert times == [1.5, 2.0, 2.5, 3.0]


def test_the_clock_executor_is_one_worker_whose_jobs_take_clock_time() -> None:
    clock = FakeClock()
    executor = ClockExecutor(clock, job_seconds=2.0)
    finished: List[Tuple[str, float]] = []
    executor.submit(lambda: finished.append(("first", clock.now())))
    clock.advance_to(1.0)
    executor.submit(lambda: finished.append(("second", clock.now())))
    clock.advance_to(10.0)
    executor.submit(lambda: finished.append(("third", clock.now())))
    clock.advance_to(20.0)
    assert finished == [("first", 2.0), ("second", 4.0), ("third", 12.0)]


def test_publisher_status_follows_registrations_and_live_connections() -> None:
    bus = InMemoryBus()
    topic = "/soundDetection/signal"
    assert bus.publisher_status(topic) is PublisherStatus.NONE
    first = bus.advertise(topic, String, node="soundDetection")
    assert bus.publisher_status(topic) is PublisherStatus.CONNECTED
    first.crash()
    assert bus.publisher_status(topic) is PublisherStatus.STALE
    restarted = bus.advertise(topic, String, node="soundDetection")
    assert bus.publisher_status(topic) is PublisherStatus.CONNECTED
    first.shutdown()  # the stale one leaving does not remove the registration that replaced it
    assert bus.publisher_status(topic) is PublisherStatus.CONNECTED
    restarted.shutdown()
    assert bus.publisher_status(topic) is PublisherStatus.NONE


def test_the_bus_delivers_to_every_subscriber_and_a_dead_publisher_cannot_publish() -> None:
    bus = InMemoryBus()
    received: List[str] = []
    bus.subscribe("/t", String, lambda message: received.append("1:" + message.data))  # type: ignore[attr-defined]
    bus.subscribe("/t", String, lambda message: received.append("2:" + message.data))  # type: ignore[attr-defined]
    publisher = bus.advertise("/t", String, node="talker")
    publisher.publish(String("hi"))
    assert received == ["1:hi", "2:hi"]
    publisher.crash()
    with pytest.raises(RuntimeError) as error:
        publisher.publish(String("again"))
    assert str(error.value) == "talker published on /t after it went down"
