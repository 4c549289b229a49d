"""Bounded connections for the viewer's HTTP server: a fixed pool of worker threads and a deadline on
every request's line and headers (issue #33 item 9).

``ThreadingHTTPServer`` starts one thread per connection and waits for a request as long as the client
likes: 100 idle sockets held 103 threads for as long as they stayed open, and a client sending one header
byte per second kept its connection (and thread) indefinitely. Here:

- at most :attr:`BoundedHTTPServer.workers` threads serve connections, started as needed (daemon threads:
  Ctrl-C never waits for a browser's open keep-alive connection); up to ``waiting`` more connections
  wait in a queue; beyond that a connection is answered ``503`` and closed at once, on the accepting
  thread, without reading it;
- a request's line and headers must all arrive within ``header_seconds`` of the connection being
  accepted (or of the previous response, on a keep-alive connection: so an idle connection is closed
  after that time too). The limit is on the total, not per read, so trickling one byte a second does not
  extend it. A connection that waited in the queue past its deadline still gets ``grace_seconds`` to be
  read (its request is usually in the kernel's buffer already), so every connection is closed within
  ``header_seconds + ceil(waiting / workers) * grace_seconds`` unless it sends a complete request;
- a response must be taken by the client within ``write_seconds``.
"""
from __future__ import annotations

import io
import logging
import queue
import socket
import threading
import time
from http.server import BaseHTTPRequestHandler, HTTPServer

log = logging.getLogger(__name__)

BUSY = (b"HTTP/1.1 503 Service Unavailable\r\nContent-Type: text/plain\r\nContent-Length: 32\r\n"
        b"Retry-After: 1\r\nConnection: close\r\n\r\ntoo many connections; try again\n")


class _DeadlineReader(io.RawIOBase):
    """The socket's reading side, each read bounded by what is left of the handler's ``deadline``."""

    def __init__(self, sock, handler):
        super().__init__()
        self._sock = sock
        self._handler = handler

    def readable(self):
        return True

    def readinto(self, buf):
        left = self._handler.deadline - time.monotonic()
        if left <= 0:
            raise TimeoutError("no complete request in time")
        self._sock.settimeout(left)
        return self._sock.recv_into(buf)


class TimedHandler(BaseHTTPRequestHandler):
    """A request handler whose request line and headers must arrive by a deadline (see the module)."""

    def __init__(self, request, client_address, server, accepted=None):
        self._accepted = time.monotonic() if accepted is None else accepted
        self._first = True
        self.deadline = 0.0
        super().__init__(request, client_address, server)

    def setup(self):
        super().setup()
        self.rfile.close()  # the socket's own file, which would wait forever: replaced by a deadline-bound one
        self.rfile = io.BufferedReader(_DeadlineReader(self.connection, self))

    def handle_one_request(self):
        now = time.monotonic()
        if self._first:  # counted from the accept: time spent in the queue is part of the allowance
            self.deadline = max(self._accepted + self.server.header_seconds, now + self.server.grace_seconds)
            self._first = False
        else:  # keep-alive: the next request (or the idle connection's end) within the same time
            self.deadline = now + self.server.header_seconds
        super().handle_one_request()

    def parse_request(self):
        ok = super().parse_request()
        self.connection.settimeout(self.server.write_seconds)  # the headers are in: the response's own limit
        return ok


class BoundedHTTPServer(HTTPServer):
    """``HTTPServer`` with a bounded pool of daemon worker threads and a bounded waiting queue.

    The handler class must accept an ``accepted`` keyword (:class:`TimedHandler` does).
    """

    workers = 16            # threads serving connections (a browser opens at most 6 per host)
    waiting = 48            # connections queued for a worker; more are answered 503 at once
    header_seconds = 5.0    # a request's line and headers, and a keep-alive connection's idle time
    grace_seconds = 0.25    # reading time left to a connection that waited in the queue past its deadline
    write_seconds = 60.0    # for the client to take a response
    request_queue_size = 128  # the listen backlog (socketserver's 5 would stall connects before the 503)

    def __init__(self, server_address, handler_class):
        # the pool first: a failed bind calls server_close from inside HTTPServer.__init__
        self._jobs = queue.SimpleQueue()
        self._slots = threading.BoundedSemaphore(self.workers + self.waiting)
        self._lock = threading.Lock()
        self._threads = self._idle = self._pending = 0
        self._open = set()  # connections queued or being served: shut down by server_close
        super().__init__(server_address, handler_class)

    def process_request(self, request, client_address):
        if not self._slots.acquire(blocking=False):
            return self._refuse(request)
        with self._lock:
            self._open.add(request)
            self._pending += 1
            start = self._pending > self._idle and self._threads < self.workers
            self._threads += start
            n = self._threads
        self._jobs.put((request, client_address, time.monotonic()))
        if start:
            threading.Thread(target=self._work, name=f"autobones-view-{self.server_address[1]}-{n}",
                             daemon=True).start()
        return None

    def _refuse(self, request):
        try:  # never blocks the accepting thread: whatever the socket takes at once, then closed
            request.setblocking(False)
            request.send(BUSY)
        except OSError:
            pass
        log.debug("refused a connection: %d served or waiting", self.workers + self.waiting)
        self.shutdown_request(request)

    def _work(self):
        while True:
            with self._lock:
                self._idle += 1
            job = self._jobs.get()
            with self._lock:
                self._idle -= 1
                self._pending -= job is not None
            if job is None:  # server_close
                return
            request, address, accepted = job
            try:
                self.RequestHandlerClass(request, address, self, accepted=accepted)
            except Exception:  # noqa: BLE001 - one connection's failure must not end the worker
                self.handle_error(request, address)
            finally:
                with self._lock:
                    self._open.discard(request)
                self.shutdown_request(request)
                self._slots.release()

    def handle_error(self, request, client_address):
        # a client that hung up or timed out is routine: one line at debug level, never a traceback on stderr
        log.debug("connection from %s ended by an error", client_address, exc_info=True)

    def thread_count(self):
        """Worker threads started so far (at most :attr:`workers`)."""
        with self._lock:
            return self._threads

    def server_close(self):
        """Close the listening socket, end every queued or open connection and stop the workers."""
        super().server_close()
        with self._lock:
            conns, threads = list(self._open), self._threads
        for c in conns:
            try:
                c.shutdown(socket.SHUT_RDWR)  # a worker waiting on it reads the end at once
            except OSError:
                pass
        for _ in range(threads):
            self._jobs.put(None)
