"""Running the command line: finding the program, running it to completion or
in the background with its progress, turning its failures into one message.

No bpy here: the operator turns CommandError into self.report({'ERROR'}, ...)."""

import os
import re
import shutil
import subprocess
import threading

try:                      # a pseudo-terminal on stderr makes the program draw
    import pty            # its progress bar (it draws one only on a terminal)
except ImportError:       # Windows: no progress, a spinner
    pty = None


class CommandError(Exception):
    """A failure to show the user as it is (no traceback)."""


def find_program(program):
    """The absolute path of the weathering program: `program` itself when it
    names a path, else found on PATH. Raises CommandError."""
    name = os.path.expanduser((program or "").strip())
    where = "set it in Edit > Preferences > Add-ons > Weathering"
    if not name:
        raise CommandError("no weathering program is set: %s" % where)
    if os.sep in name or (os.altsep and os.altsep in name):
        if not os.path.isfile(name):
            raise CommandError("the weathering program %s does not exist: %s" % (name, where))
        if not os.access(name, os.X_OK):
            raise CommandError("the weathering program %s is not executable: %s" % (name, where))
        return os.path.abspath(name)
    found = shutil.which(name)
    if found is None:
        raise CommandError("the weathering program '%s' is not on PATH: %s (its absolute path, "
                           "e.g. /path/to/weathering/build/weathering)" % (name, where))
    return found


# "simulate   [#########.....................]  30.0%     1.2s  eta    2.8s "
PROGRESS = re.compile(r"([^\r\n\[\]]*?)\s*\[([#.]+)\]\s*([0-9.]+)%")

# Each phase's share of a run's progress bar (labels as the program prints them).
_PHASES = (("bake", 0.0, 0.1), ("simulate", 0.1, 0.6), ("masks", 0.7, 0.1),
           ("gather", 0.8, 0.1), ("texture", 0.9, 0.1))


def overall_fraction(label, fraction):
    """A phase's progress as a share of the whole run, in [0, 1]."""
    for name, start, share in _PHASES:
        if label.startswith(name):
            return start + share * min(max(fraction, 0.0), 1.0)
    return None


def messages(text):
    """The lines of the program's stderr without its progress bars."""
    lines = []
    for line in re.split(r"[\r\n]+", text):
        line = PROGRESS.sub("", line).strip()
        if line:
            lines.append(line)
    return lines


def failure(args, status, stderr):
    """CommandError for a command that exited with `status`."""
    lines = messages(stderr)
    what = "weathering %s" % (args[1] if len(args) > 1 else "")
    detail = " / ".join(lines[-4:]) if lines else "no message on stderr"
    kind = "bad input" if status == 2 else "failed"
    return CommandError("%s: %s (exit status %d): %s" % (what.strip(), kind, status, detail))


def run(args, cwd, timeout=600):
    """Runs a short command (init, split) to completion: its stdout.
    Raises CommandError when it cannot start or exits non-zero."""
    try:
        done = subprocess.run(args, cwd=cwd, stdin=subprocess.DEVNULL, capture_output=True,
                              text=True, timeout=timeout)
    except FileNotFoundError:
        raise CommandError("cannot run %s: no such program" % args[0])
    except PermissionError:
        raise CommandError("cannot run %s: permission denied" % args[0])
    except subprocess.TimeoutExpired:
        raise CommandError("%s did not finish within %d s" % (" ".join(args[:2]), timeout))
    except OSError as e:
        raise CommandError("cannot run %s: %s" % (args[0], e.strerror or e))
    if done.returncode != 0:
        raise failure(args, done.returncode, done.stderr)
    return done.stdout, done.stderr


class Process:
    """A long command (run) in the background: poll() it from a timer.

    stdout goes to `log` (a file path); stderr is read by a thread, through a
    pseudo-terminal when `progress` is asked for and the platform has one, so
    that the program draws its progress bar; label/fraction follow it."""

    def __init__(self, args, cwd, log, progress=True):
        self.args = args
        self.label = ""
        self.fraction = None          # of the whole run, None while unknown
        self._chunks = []
        self._lock = threading.Lock()
        self._log = open(log, "w", encoding="utf-8")
        master = slave = None
        try:
            if progress and pty is not None:
                master, slave = pty.openpty()
                stderr = slave
            else:
                stderr = subprocess.PIPE
            self._proc = subprocess.Popen(args, cwd=cwd, stdin=subprocess.DEVNULL,
                                          stdout=self._log, stderr=stderr)
        except FileNotFoundError:
            self._close(master, slave)
            raise CommandError("cannot run %s: no such program" % args[0])
        except OSError as e:
            self._close(master, slave)
            raise CommandError("cannot run %s: %s" % (args[0], e.strerror or e))
        if slave is not None:
            os.close(slave)
            self._reader = threading.Thread(target=self._read_fd, args=(master,), daemon=True)
        else:
            self._reader = threading.Thread(target=self._read_pipe, args=(self._proc.stderr,),
                                            daemon=True)
        self._reader.start()

    def _close(self, *fds):
        self._log.close()
        for fd in fds:
            if fd is not None:
                os.close(fd)

    def _add(self, data):
        with self._lock:
            self._chunks.append(data.decode("utf-8", "replace"))

    def _read_fd(self, fd):
        try:
            while True:
                try:
                    data = os.read(fd, 4096)
                except OSError:           # EIO: the child closed the terminal
                    break
                if not data:
                    break
                self._add(data)
        finally:
            os.close(fd)

    def _read_pipe(self, pipe):
        for data in iter(lambda: pipe.read1(4096), b""):
            self._add(data)
        pipe.close()

    @property
    def stderr(self):
        with self._lock:
            return "".join(self._chunks)

    def poll(self):
        """None while running, else the exit status. Updates label/fraction."""
        text = self.stderr
        tail = text[-400:]
        matches = list(PROGRESS.finditer(tail))
        if matches:
            m = matches[-1]
            label = m.group(1).strip()
            try:
                phase = float(m.group(3)) / 100.0
            except ValueError:
                phase = 0.0
            self.label = "%s %.0f%%" % (label, 100.0 * phase)
            fraction = overall_fraction(label, phase)
            if fraction is not None:
                self.fraction = max(fraction, self.fraction or 0.0)
        status = self._proc.poll()
        if status is not None:
            self._reader.join(timeout=5)
            if not self._log.closed:
                self._log.write(self.stderr)
                self._log.close()
        return status

    def wait(self):
        self._proc.wait()
        return self.poll()

    def cancel(self):
        if self._proc.poll() is None:
            self._proc.terminate()
            try:
                self._proc.wait(timeout=5)
            except subprocess.TimeoutExpired:
                self._proc.kill()
                self._proc.wait()
        self.poll()

    def check(self):
        """Raises CommandError when the finished command failed."""
        status = self.poll()
        if status is not None and status != 0:
            if status < 0:
                raise CommandError("weathering %s was stopped (signal %d)"
                                   % (self.args[1], -status))
            raise failure(self.args, status, self.stderr)
