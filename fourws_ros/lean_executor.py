# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""A single-threaded executor for the nodes whose callbacks take rclpy's message info (the
controller, the recorder, the realtime simulator: a message's publisher is told by it).

rclpy's C++ events executor cannot deliver message info (a callback that takes it fails with
``SystemError``), so those nodes spin rclpy's :class:`~rclpy.executors.SingleThreadedExecutor`,
which on every wake-up gathers the node's entities into lists, enters each handle through an
``ExitStack``, builds a wait set, and runs every ready callback as a task with its own future
and a generator between them. A lockstep tick wakes the controller about three times; a
profile of the default graph's controller put 1.0 ms of its 1.3 ms of CPU per tick in that
machinery, and the controller was the busiest of the run's processes.

:class:`LeanExecutor` keeps rclpy's executor (its guard conditions, shutdown, nodes,
``spin_until_future_complete``) and replaces one wake-up: it waits on the nodes'
subscriptions, timers, clients, services and guard conditions, then calls every ready
callback directly, in rclpy's order (timers, subscriptions, guard conditions, clients'
responses, services).
Each handle is held (entered) for the wait as rclpy does, so an entity destroyed meanwhile by
another thread is skipped, never used. A node with what the lean path does not handle (a
waitable such as a QoS event handler or an action, a coroutine callback, a callback group
that refuses) takes rclpy's own path for that wake-up, so behaviour never depends on
which path ran: the same callbacks, with the same arguments, in the same order.

The nodes' entity lists (and the checks above) are gathered once and kept until something
changes: rclpy wakes the executor (:meth:`wake`) on every entity a node creates or destroys
and on every node added or removed, and that, or a wake-up on rclpy's path, drops them. A
callback group refuses only while rclpy's path runs one of its callbacks, so it is asked
whenever the lists are gathered again; a callback swapped for a coroutine on an existing
entity is not seen until then. Gathering them on every wake-up cost the controller of a
lockstep run about a tenth of its CPU (two to three wake-ups a tick).
"""

from __future__ import annotations

import inspect
from typing import Any, Callable

from rclpy.exceptions import InvalidHandle, TimerCancelledError
from rclpy.executors import (ExternalShutdownException, SingleThreadedExecutor,
                             TimeoutObject)
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.subscription import Subscription
from rclpy.timer import TimerInfo
from rclpy.utilities import timeout_sec_to_nsec

_MESSAGE_ONLY = Subscription.CallbackType.MessageOnly


def _timer_info_arg(callback: Callable[..., Any]) -> str | None:
    """The parameter of a timer callback annotated TimerInfo (rclpy passes it by name)."""
    try:
        params = inspect.signature(callback).parameters.values()
    except (TypeError, ValueError):
        return None
    for param in params:
        if param.annotation == TimerInfo:  # as rclpy compares it (a string never matches)
            return param.name
    return None


class LeanExecutor(SingleThreadedExecutor):
    """rclpy's single-threaded executor with a shorter wake-up (module docstring)."""

    def __init__(self, *, context: Any = None) -> None:
        super().__init__(context=context)
        #: Wake-ups taken by the lean path and by rclpy's own (tests, benchmarks).
        self.lean_wakeups = 0
        self.rclpy_wakeups = 0
        #: Times the nodes' entities were gathered (the cache below missed).
        self.entity_scans = 0
        self._entities: tuple[list, list, list, list, list] | None = None
        # changes signalled (wake, add_node, remove_node) and the count the entities were
        # gathered at: a change while they are being gathered (another thread creating an
        # entity) leaves the counts apart, so they are gathered again
        self._changes = 0
        self._gathered_at = -1
        self._plain: dict[int, bool] = {}  # id(callback) -> a plain (non-coroutine) function
        self._timer_args: dict[int, str | None] = {}

    def _is_plain(self, callback: Any) -> bool:
        key = id(callback)
        plain = self._plain.get(key)
        if plain is None:
            func = getattr(callback, "__func__", callback)
            plain = not (inspect.iscoroutinefunction(func) or inspect.isasyncgenfunction(func))
            if len(self._plain) > 256:
                self._plain.clear()
            self._plain[key] = plain
        return plain

    def wake(self) -> None:
        """rclpy's wake-up on a created or destroyed entity: the entities are gathered again."""
        self._changes += 1
        super().wake()

    def add_node(self, node: Any) -> bool:  # noqa: D102 - rclpy's, the entities gathered again
        self._changes += 1
        return super().add_node(node)

    def remove_node(self, node: Any) -> None:  # noqa: D102 - rclpy's, as add_node
        self._changes += 1
        super().remove_node(node)

    def _lean_entities(self) -> tuple[list, list, list, list, list] | None:
        """The nodes' subscriptions, timers, clients, services and guard conditions, as last
        gathered while nothing changed since; None where one needs rclpy's own path."""
        changes = self._changes
        if self._gathered_at != changes:
            self.entity_scans += 1
            self._entities = self._gather()
            self._gathered_at = changes
        return self._entities

    def _gather(self) -> tuple[list, list, list, list, list] | None:
        subs: list = []
        timers: list = []
        clients: list = []
        services: list = []
        guards: list = []
        for node in self.get_nodes():
            # Node's entity properties are generators or lists, depending on the entity
            if any(True for _ in node.waitables):
                return None
            node_subs, node_timers = list(node.subscriptions), list(node.timers)
            node_services, node_guards = list(node.services), list(node.guards)
            node_clients = list(node.clients)
            for entity in (*node_subs, *node_timers, *node_clients, *node_services,
                           *node_guards):
                group = entity.callback_group
                if group is not None and not group.can_execute(entity):
                    return None
                # a client has no callback (its futures get the responses)
                callback = getattr(entity, "callback", None)
                if callback is not None and not self._is_plain(callback):
                    return None
            subs.extend(node_subs)
            timers.extend(node_timers)
            clients.extend(node_clients)
            services.extend(node_services)
            guards.extend(node_guards)
        return subs, timers, clients, services, guards

    def _spin_once_impl(self, timeout_sec: Any = None,
                        wait_condition: Callable[[], bool] = lambda: False) -> None:
        entities = self._lean_entities()
        if entities is None or self._is_shutdown:
            self.rclpy_wakeups += 1
            self._gathered_at = -1  # its tasks and callback groups: gathered again next time
            super()._spin_once_impl(timeout_sec, wait_condition)
            return
        self.lean_wakeups += 1
        subs, timers, clients, services, node_guards = entities
        timeout = timeout_sec.timeout if isinstance(timeout_sec, TimeoutObject) else timeout_sec
        for gc in node_guards:
            # a trigger a previous wake-up took but did not handle (rclpy does the same)
            if gc._executor_triggered:
                gc.trigger()
        own = [g for g in (self._guard, self._sigint_gc) if g]
        entered: list = []
        try:
            held = []
            for kind in (subs, timers, clients, services, node_guards, own):
                kept = []
                for entity in kind:
                    try:
                        entity.handle.__enter__()
                    except InvalidHandle:
                        continue
                    entered.append(entity.handle)
                    kept.append(entity)
                held.append(kept)
            subs, timers, clients, services, node_guards, own = held
            context_handle = self._context.handle
            if context_handle is None:
                raise RuntimeError("Cannot enter context if context is None")
            context_handle.__enter__()
            entered.append(context_handle)
            wait_set = _rclpy.WaitSet(len(subs), len(node_guards) + len(own), len(timers),
                                      len(clients), len(services), 0, context_handle)
            for sub in subs:
                wait_set.add_subscription(sub.handle)
            for cli in clients:
                wait_set.add_client(cli.handle)
            for srv in services:
                wait_set.add_service(srv.handle)
            for tmr in timers:
                wait_set.add_timer(tmr.handle)
            for gc in (*node_guards, *own):
                wait_set.add_guard_condition(gc.handle)
            wait_set.wait(timeout_sec_to_nsec(timeout))
            if self._is_shutdown:
                return
            if not self._context.ok():
                raise ExternalShutdownException()
            subs_ready = set(wait_set.get_ready_entities("subscription"))
            timers_ready = set(wait_set.get_ready_entities("timer"))
            clients_ready = set(wait_set.get_ready_entities("client"))
            services_ready = set(wait_set.get_ready_entities("service"))
            guards_ready = set(wait_set.get_ready_entities("guard_condition"))
        finally:
            for handle in reversed(entered):
                handle.__exit__(None, None, None)
        for gc in node_guards:
            if gc.handle.pointer in guards_ready:
                gc._executor_triggered = True
        ready_timers = [t for t in timers if t.handle.pointer in timers_ready]
        ready_subs = [s for s in subs if s.handle.pointer in subs_ready]
        ready_guards = [g for g in node_guards if g._executor_triggered]
        ready_clients = [c for c in clients if c.handle.pointer in clients_ready]
        ready_services = [s for s in services if s.handle.pointer in services_ready]
        for tmr in ready_timers:
            self._run_timer(tmr)
        for sub in ready_subs:
            self._run_subscription(sub)
        for gc in ready_guards:
            gc._executor_triggered = False
            if gc.callback:
                gc.callback()
        for cli in ready_clients:
            self._run_client(cli)
        for srv in ready_services:
            self._run_service(srv)

    def _run_timer(self, tmr: Any) -> None:
        try:
            with tmr.handle:
                if not tmr.handle.is_timer_ready():
                    return
                info = tmr.handle.call_timer_with_info()
        except (InvalidHandle, TimerCancelledError):
            return
        callback = tmr.callback
        if not callback:
            return
        key = id(callback)
        if key not in self._timer_args:
            self._timer_args[key] = _timer_info_arg(callback)
        arg = self._timer_args[key]
        if arg is None:
            callback()
        else:
            callback(**{arg: TimerInfo(expected_call_time=info["expected_call_time"],
                                       actual_call_time=info["actual_call_time"],
                                       clock_type=tmr.clock.clock_type)})

    @staticmethod
    def _take(entity: Any, take: Callable[[Any], Any]) -> Any:
        """``take(handle)`` with the entity's handle held; None if the entity is destroyed."""
        try:
            with entity.handle:
                return take(entity.handle)
        except InvalidHandle:
            return None

    def _run_subscription(self, sub: Any) -> None:
        taken = self._take(sub, lambda h: h.take_message(sub.msg_type, sub.raw))
        if taken is None:
            return
        if sub._callback_type is _MESSAGE_ONLY:
            sub.callback(taken[0])
        else:
            sub.callback(*taken)

    def _run_client(self, cli: Any) -> None:
        header, response = self._take(
            cli, lambda h: h.take_response(cli.srv_type.Response)) or (None, None)
        if header is None:
            return
        try:
            future = cli.get_pending_request(header.request_id.sequence_number)
        except KeyError:  # the request was cancelled
            return
        future._set_executor(self)
        future.set_result(response)

    def _run_service(self, srv: Any) -> None:
        request, header = self._take(
            srv, lambda h: h.service_take_request(srv.srv_type.Request)) or (None, None)
        if header is None:
            return
        response = srv.callback(request, srv.srv_type.Response())
        srv.send_response(response, header)


__all__ = ["LeanExecutor"]
