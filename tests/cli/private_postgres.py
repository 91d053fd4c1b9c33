"""A private PostgreSQL 15 server for the CLI tests: initdb in a directory of the test (as the
postgres user when run as root), trust authentication for the role csgtile, 127.0.0.1 on a
free port (city_run.py, sigterm_grace.py; chaos_workers.py starts its own inline, the same way)."""
import os
import shutil
import socket
import subprocess

PG_BIN = "/usr/lib/postgresql/15/bin"


def available():
    return os.path.exists(f"{PG_BIN}/initdb")


class PrivatePostgres:
    def __init__(self, directory):
        with socket.socket() as sock:
            sock.bind(("127.0.0.1", 0))
            self.port = sock.getsockname()[1]
        self.dir = directory
        os.makedirs(directory)
        self.as_pg = ["runuser", "-u", "postgres", "--"] if os.geteuid() == 0 else []
        if self.as_pg:
            shutil.chown(directory, "postgres")
        subprocess.run(self.as_pg + [f"{PG_BIN}/initdb", "-D", f"{directory}/data", "-A", "trust",
                                     "-U", "csgtile"], check=True, capture_output=True)
        self.ctl("-o", f"-p {self.port} -k {directory} -c listen_addresses=127.0.0.1",
                 "-l", f"{directory}/log", "-w", "start")

    def ctl(self, *args):
        subprocess.run(self.as_pg + [f"{PG_BIN}/pg_ctl", "-D", f"{self.dir}/data", *args],
                       check=True, capture_output=True)

    def queue_yaml(self):
        """The lines of a config's `queue:` section that select this server."""
        return (f"  backend: postgres\n  postgres_dsn: \"host=127.0.0.1 port={self.port} "
                f"dbname=postgres user=csgtile connect_timeout=5\"\n")

    def query(self, sql):
        """Rows of `sql` (psql -At): one string per row, columns separated by a space."""
        p = subprocess.run([f"{PG_BIN}/psql", "-h", "127.0.0.1", "-p", str(self.port), "-U",
                            "csgtile", "-d", "postgres", "-At", "-F", " ", "-c", sql],
                           check=True, capture_output=True, text=True)
        return p.stdout.splitlines()

    def stop(self):
        subprocess.run(self.as_pg + [f"{PG_BIN}/pg_ctl", "-D", f"{self.dir}/data", "-m",
                                     "immediate", "stop"], capture_output=True)
