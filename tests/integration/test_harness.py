"""Self-checks of the suite's own waiting rule (conftest.Deadline): a stall of the whole machine does not use up a
wait, a slow loop does not stretch it without end, and a wait for something that never comes still ends."""
import conftest
from conftest import Deadline


class FakeClock:
    def __init__(self):
        self.t = 1000.0

    def __call__(self):
        return self.t


def test_deadline_expires_on_time_when_polled_often(monkeypatch):
    clock = FakeClock()
    monkeypatch.setattr(conftest.time, "monotonic", clock)
    d = Deadline(2.0)
    polls = 0
    while not d.expired():
        clock.t += 0.01
        polls += 1
    assert 199 <= polls <= 201 and d.extended == 0.0
    assert str(d) == "2.0 s"


def test_a_stall_does_not_count(monkeypatch):
    clock = FakeClock()
    monkeypatch.setattr(conftest.time, "monotonic", clock)
    d = Deadline(2.0)
    clock.t += 0.5
    assert abs(d.left() - 2.0) < 1e-9       # 0.5 s without a check: the guest did not run, nothing is used up
    clock.t += 0.2
    assert abs(d.left() - 1.8) < 1e-9       # 0.2 s between checks: normal waiting, counted
    clock.t += 10.0
    assert not d.expired()                  # a 10 s stall of the whole machine
    assert abs(d.extended - 10.5) < 1e-9
    assert "+10.5 s of stalls" in str(d)
    assert d.slice() == Deadline.POLL_S


def test_stalls_extend_a_wait_by_at_most_the_cap(monkeypatch):
    clock = FakeClock()
    monkeypatch.setattr(conftest.time, "monotonic", clock)
    d = Deadline(1.0)
    steps = 0
    while not d.expired():                  # every check late: a loop that never comes round in time
        clock.t += 1.0
        steps += 1
    assert d.extended == Deadline.MAX_EXTENSION_S
    assert steps == Deadline.MAX_EXTENSION_S + 1


def test_until_returns_the_first_true_result_or_the_last_after_the_deadline(monkeypatch):
    clock = FakeClock()
    monkeypatch.setattr(conftest.time, "monotonic", clock)
    monkeypatch.setattr(conftest.time, "sleep", lambda s: setattr(clock, "t", clock.t + s))
    calls = []
    assert Deadline(1.0).until(lambda: calls.append(clock.t) or (len(calls) == 5 and "found")) == "found"
    assert len(calls) == 5
    calls.clear()
    assert Deadline(1.0).until(lambda: calls.append(clock.t) or None, step=0.1) is None
    assert 10 <= len(calls) <= 12 and calls[-1] - calls[0] >= 1.0 - 1e-9  # checked once more at the deadline
