// What a client receives, recorded to CSV as the C++ SDK's recorder writes it (docs/recorder.md,
// sdk/recorder/src/csv_writer.cpp): one file of samples, a header row and one row per State
// accepted, the columns in the same order; one file of events beside it (NAME.events.csv) with
// the server's events and the connection's changes. Doubles with 17 significant digits, so each
// reads back as the same double; NaN as "NaN". HDF5 needs the C++ SDK's library: refused here.
using System;
using System.Collections.Generic;
using System.Globalization;
using System.IO;
using System.Text;
using System.Threading;

namespace Hapticd
{
    /// <summary>Records what a client receives into CSV (docs/recorder.md): every State it
    /// accepts, and the server's events. Dispose (or Close) drains, flushes and closes the files.</summary>
    public sealed class Recorder : IDisposable
    {
        private const int ConnectionKindBase = 100;  // events.csv's kind of a connection change (record_format.hpp)
        private static readonly string[] EventNames = { "unknown", "session_opened", "session_closed", "lease_expired",
                                                        "scene_changed", "force_fault", "watch_started", "device_fault", "reset" };
        private static readonly string[] ConnectionNames = { "connection_connected", "connection_lost", "connection_resumed", "connection_ended" };
        private const ulong MaxQueueCapacity = 1UL << 24;

        private readonly object gate_ = new object();
        private readonly Queue<State> samples_ = new Queue<State>();           // guarded by gate_
        private readonly Queue<string> events_ = new Queue<string>();          // guarded by gate_: rows
        private readonly ulong capacity_;
        private RecorderStats stats_;                                          // guarded by gate_
        private StreamWriter samplesFile_, eventsFile_;                        // the writer thread's
        private Thread writer_;
        private bool stopping_;                                                // guarded by gate_
        private StateLink link_;
        private Action<State> tap_;
        private EventWatch watch_;                                             // guarded by gate_
        private List<Recorder> owner_;  // the client's recorders, which its connection changes reach

        public string Path { get; private set; }
        public string EventsPath { get; private set; }

        internal Recorder(RecorderOptions options)
        {
            string path = options.Path ?? "";
            if (path.Length == 0) throw new HapticException(ErrorCode.InvalidArgument, "record: path: empty");
            if (options.QueueCapacity == 0) throw new HapticException(ErrorCode.InvalidArgument, "record: queue_capacity: must be >= 1");
            if (options.QueueCapacity > MaxQueueCapacity)
            {
                throw new HapticException(ErrorCode.InvalidArgument, "record: queue_capacity: " + options.QueueCapacity + " is more than " + MaxQueueCapacity);
            }
            string extension = System.IO.Path.GetExtension(path).ToLowerInvariant();
            var format = options.Format;
            if (format == RecorderFormat.Auto)
            {
                if (extension == ".csv") format = RecorderFormat.Csv;
                else if (extension == ".h5" || extension == ".hdf5") format = RecorderFormat.Hdf5;
                else
                {
                    throw new HapticException(ErrorCode.InvalidArgument, "record: path: '" + path +
                        "' ends in neither .csv nor .h5 or .hdf5; name the format (RecorderOptions.Format)");
                }
            }
            if (format == RecorderFormat.Hdf5)
            {
                throw new HapticException(ErrorCode.InvalidArgument, "record: format: HDF5 is written by the C++ SDK's recorder " +
                    "(libhaptic_c); the C# client writes CSV (a .csv path)");
            }
            if (format != RecorderFormat.Csv) throw new HapticException(ErrorCode.InvalidArgument, "record: format: unknown value " + (int)format);
            string directory = System.IO.Path.GetDirectoryName(path);
            if (string.IsNullOrEmpty(directory)) directory = ".";
            if (!Directory.Exists(directory)) throw new HapticException(ErrorCode.InvalidArgument, "record: path: the directory '" + directory + "' does not exist");
            string eventsPath = options.Events ? System.IO.Path.Combine(System.IO.Path.GetDirectoryName(path) ?? "",
                                                                        System.IO.Path.GetFileNameWithoutExtension(path) + ".events.csv") : "";
            if (!options.Overwrite)
            {
                foreach (var name in new[] { path, eventsPath })
                {
                    if (name.Length > 0 && File.Exists(name))
                    {
                        throw new HapticException(ErrorCode.InvalidArgument, "record: path: '" + name + "' exists (RecorderOptions.Overwrite replaces it)");
                    }
                }
            }
            Path = path;
            EventsPath = eventsPath;
            capacity_ = options.QueueCapacity;
            var mode = options.Overwrite ? FileMode.Create : FileMode.CreateNew;
            try
            {
                samplesFile_ = new StreamWriter(new FileStream(path, mode, FileAccess.Write), new UTF8Encoding(false)) { NewLine = "\n" };
                if (eventsPath.Length > 0)
                {
                    eventsFile_ = new StreamWriter(new FileStream(eventsPath, mode, FileAccess.Write), new UTF8Encoding(false)) { NewLine = "\n" };
                }
            }
            catch (IOException e)
            {
                CloseFiles();
                try { File.Delete(path); } catch (Exception) { }
                throw new HapticException(ErrorCode.InvalidArgument, "record: path: cannot create '" + path + "': " + e.Message);
            }
            // The header rows from the start: a file that makes sense whenever the process ends.
            samplesFile_.Write("received_ns,arrived_ns,tick,sequence,server_time_s,position_x_m,position_y_m,position_z_m," +
                               "velocity_x_m_s,velocity_y_m_s,velocity_z_m_s,force_x_N,force_y_N,force_z_N,proxy_x_m,proxy_y_m," +
                               "proxy_z_m,contact_count,flags,buttons,orientation_w,orientation_x,orientation_y,orientation_z," +
                               "torque_x_Nm,torque_y_Nm,torque_z_Nm,age_ns\n");
            samplesFile_.Flush();
            if (eventsFile_ != null)
            {
                eventsFile_.Write("received_ns,kind,kind_name,session_id,server_time_s,item_id,message\n");
                eventsFile_.Flush();
            }
            writer_ = new Thread(WriteLoop) { IsBackground = true, Name = "hapticd recorder" };
            writer_.Start();
        }

        ~Recorder() { Close(); }

        /// <summary>The server's events from now on, through `watch` (opened by the client).</summary>
        internal void WatchEvents(EventWatch watch)
        {
            lock (gate_) watch_ = watch;
        }

        /// <summary>After its client reopened a session (the server restarted): the old stream
        /// ended with the old server, so the events are watched again on the new one, as the C++
        /// SDK's observers are. Where the new server refuses, the events stay off, and the
        /// connection's changes still say why.</summary>
        internal void WatchEventsAgain(Func<Action<Event>, EventWatch> open)
        {
            if (EventsPath.Length == 0) return;
            EventWatch fresh = null;
            try { fresh = open(AddEvent); }
            catch (HapticException) { }
            EventWatch old;
            lock (gate_)
            {
                if (stopping_)
                {
                    old = fresh;  // closed meanwhile: the new stream goes too
                }
                else
                {
                    old = watch_;
                    watch_ = fresh;
                }
            }
            if (old != null) old.End();
        }

        /// <summary>Starts taking every State the link accepts (on its receive thread: queued only),
        /// and joins `recorders`, the client's, to be told its connection changes.</summary>
        internal void Attach(StateLink link, List<Recorder> recorders)
        {
            link_ = link;
            tap_ = Enqueue;
            link.AddTap(tap_);
            owner_ = recorders;
            lock (recorders) recorders.Add(this);
        }

        private void Enqueue(State state)
        {
            lock (gate_)
            {
                if (stopping_) return;
                stats_.SamplesReceived++;
                if ((ulong)samples_.Count >= capacity_) { stats_.Dropped++; return; }
                samples_.Enqueue(state);
            }
        }

        private void EnqueueEvent(string row)
        {
            lock (gate_)
            {
                if (stopping_ || eventsFile_ == null) return;
                if ((ulong)events_.Count >= capacity_) { stats_.EventsDropped++; return; }
                events_.Enqueue(row);
                Monitor.Pulse(gate_);
            }
        }

        internal void AddEvent(Event e)
        {
            int kind = (int)e.Kind;
            EnqueueEvent(SteadyClock.Ns() + "," + kind + "," + (kind >= 0 && kind < EventNames.Length ? EventNames[kind] : "unknown") + "," +
                         e.SessionId + "," + D(e.ServerTime) + "," + e.ItemId + "," + Quoted(e.Message));
        }

        /// <summary>A change of its client's connection, as a row of the events file.</summary>
        internal void AddConnectionChange(ConnectionChange change)
        {
            int state = (int)change.State;
            EnqueueEvent(SteadyClock.Ns() + "," + (ConnectionKindBase + state) + "," +
                         (state >= 0 && state < ConnectionNames.Length ? ConnectionNames[state] : "unknown") + "," +
                         change.SessionId + ",NaN,0," + Quoted(change.Reason ?? ""));
        }

        private static string D(double v) { return double.IsNaN(v) ? "NaN" : v.ToString("G17", CultureInfo.InvariantCulture); }

        // RFC 4180: quoted, with inner quotes doubled.
        private static string Quoted(string text) { return "\"" + (text ?? "").Replace("\"", "\"\"") + "\""; }

        private static string Row(State s)
        {
            var row = new StringBuilder(512);
            row.Append(s.ReceivedAtNs).Append(',').Append(s.ArrivedAtNs != 0 ? s.ArrivedAtNs : -1).Append(',')
               .Append(s.Tick).Append(',').Append(s.Sequence).Append(',').Append(D(s.ServerTime));
            foreach (var v in new[] { s.Position, s.Velocity, s.Force, s.Proxy })
            {
                row.Append(',').Append(D(v.X)).Append(',').Append(D(v.Y)).Append(',').Append(D(v.Z));
            }
            row.Append(',').Append(s.ContactCount).Append(',').Append((uint)s.Flags).Append(',').Append(s.Buttons);
            var q = s.HasOrientation ? s.Orientation : new Quaternion(double.NaN, double.NaN, double.NaN, double.NaN);
            var t = s.HasOrientation ? s.Torque : new Vec3(double.NaN, double.NaN, double.NaN);
            row.Append(',').Append(D(q.W)).Append(',').Append(D(q.X)).Append(',').Append(D(q.Y)).Append(',').Append(D(q.Z));
            row.Append(',').Append(D(t.X)).Append(',').Append(D(t.Y)).Append(',').Append(D(t.Z));
            row.Append(',').Append(s.AgeNs).Append('\n');
            return row.ToString();
        }

        /// <summary>The writer thread: every 20 ms (or at once for an event, or to stop) it writes
        /// what has queued and flushes; a failed write is counted with the first error kept.</summary>
        private void WriteLoop()
        {
            for (;;)
            {
                State[] samples;
                string[] events;
                bool stop;
                lock (gate_)
                {
                    if (!stopping_ && samples_.Count == 0 && events_.Count == 0) Monitor.Wait(gate_, 20);
                    samples = samples_.ToArray();
                    samples_.Clear();
                    events = events_.ToArray();
                    events_.Clear();
                    stop = stopping_;
                }
                Write(samples, events);
                if (stop) return;
            }
        }

        private void Write(State[] samples, string[] events)
        {
            if (samples.Length == 0 && events.Length == 0) return;
            try
            {
                foreach (var s in samples) samplesFile_.Write(Row(s));
                samplesFile_.Flush();
                lock (gate_) stats_.SamplesWritten += (ulong)samples.Length;
                if (eventsFile_ != null && events.Length > 0)
                {
                    foreach (var e in events) { eventsFile_.Write(e); eventsFile_.Write('\n'); }
                    eventsFile_.Flush();
                    lock (gate_) stats_.EventsWritten += (ulong)events.Length;
                }
            }
            catch (IOException e)
            {
                lock (gate_)
                {
                    stats_.WriteErrors++;
                    if (string.IsNullOrEmpty(stats_.FirstError)) stats_.FirstError = e.Message;
                }
            }
        }

        public bool Recording { get { lock (gate_) return writer_ != null && !stopping_; } }

        /// <summary>The totals so far; after Close, the final ones.</summary>
        public RecorderStats Stats { get { lock (gate_) return stats_; } }

        /// <summary>Stops recording, writes what is queued, flushes and closes the files; the
        /// totals (again on later calls). A failed write is in the totals.</summary>
        public RecorderStats Close()
        {
            EventWatch watch;
            lock (gate_)
            {
                if (stopping_) return stats_;
                stopping_ = true;
                watch = watch_;
                watch_ = null;
                Monitor.Pulse(gate_);
            }
            if (owner_ != null) lock (owner_) owner_.Remove(this);
            if (link_ != null) link_.RemoveTap(tap_);
            if (watch != null) watch.End();
            if (writer_ != null && Thread.CurrentThread != writer_) writer_.Join();
            CloseFiles();
            GC.SuppressFinalize(this);
            return Stats;
        }

        private void CloseFiles()
        {
            foreach (var file in new[] { samplesFile_, eventsFile_ })
            {
                if (file == null) continue;
                try { file.Dispose(); }
                catch (IOException e)
                {
                    lock (gate_)
                    {
                        stats_.WriteErrors++;
                        if (string.IsNullOrEmpty(stats_.FirstError)) stats_.FirstError = e.Message;
                    }
                }
            }
            samplesFile_ = eventsFile_ = null;
        }

        public void Dispose() { Close(); }
    }

    /// <summary>Between and beyond the samples: the tool's position at a server time a frame
    /// needs (sdk/src/motion.cpp).</summary>
    public static class Motion
    {
        private static Vec3 Combine(double ca, Vec3 a, double cb, Vec3 b, double cc, Vec3 c)
        {
            return new Vec3(ca * a.X + cb * b.X + cc * c.X, ca * a.Y + cb * b.Y + cc * c.Y, ca * a.Z + cb * b.Z + cc * c.Z);
        }

        /// <summary>The position at server time t between samples a and b (cubic Hermite on their
        /// positions and velocities).</summary>
        public static Vec3 Interpolate(State a, State b, double t)
        {
            double h = b.ServerTime - a.ServerTime;
            if (!(h > 0.0)) return a.Position;
            double s = (t - a.ServerTime) / h, s2 = s * s, s3 = s2 * s;
            double h00 = 2 * s3 - 3 * s2 + 1, h10 = s3 - 2 * s2 + s, h01 = -2 * s3 + 3 * s2, h11 = s3 - s2;
            var p = Combine(h00, a.Position, h10 * h, a.Velocity, h01, b.Position);
            return new Vec3(p.X + h11 * h * b.Velocity.X, p.Y + h11 * h * b.Velocity.Y, p.Z + h11 * h * b.Velocity.Z);
        }

        /// <summary>The position at server time t after `latest`, with the acceleration the two
        /// newest imply.</summary>
        public static Vec3 Predict(State previous, State latest, double t)
        {
            double delta = t - latest.ServerTime;
            double h = latest.ServerTime - previous.ServerTime;
            double k = h > 0.0 ? 0.5 * delta * delta / h : 0.0;  // ½ Δ² / h, times the velocity change
            return Combine(1.0, latest.Position, delta + k, latest.Velocity, -k, previous.Velocity);
        }
    }
}
