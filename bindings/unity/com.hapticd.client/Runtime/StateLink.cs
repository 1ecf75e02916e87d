// The client's end of the UDP data plane, as the C++ SDK's sdk/src/udp_link.cpp: one socket on an
// ephemeral port; heartbeats to the server (which sends State to the address they come from, once
// a path challenge from there has been answered); authenticated State datagrams in, counted (lost,
// reordered, duplicated, rejected), the newest kept for polling and handed to the callback on the
// receive thread; the server's clock estimated from the samples' stamps (ClockSync).
using System;
using System.Collections.Generic;
using System.Diagnostics;
using System.Net;
using System.Net.Sockets;
using System.Threading;

namespace Hapticd
{
    /// <summary>The steady clock of State's local times: nanoseconds of Stopwatch.</summary>
    internal static class SteadyClock
    {
        private static readonly double NsPerTick = 1e9 / Stopwatch.Frequency;
        internal static long Ns() { return (long)(Stopwatch.GetTimestamp() * NsPerTick); }
    }

    /// <summary>The server's clock seen from the client, NTP-style over the state stream (as
    /// sdk/src/clock_sync.cpp): per window of samples the largest server − receipt is the offset
    /// (biased low by the smallest one-way delay); the windows' points give the drift.</summary>
    internal sealed class ClockSync
    {
        private const int Window = 2000;
        private const int Points = 16;
        private long windowBest_ = long.MinValue, windowBestLocal_, estimate_ = long.MinValue;
        private int windowCount_, pointCount_, nextPoint_;
        private readonly long[] pointLocal_ = new long[Points], pointOffset_ = new long[Points];
        private double? drift_;

        /// <summary>Adds a sample; returns how much longer than the quickest recent one it took (ns).</summary>
        internal long Add(long serverNs, long localNs)
        {
            long serverMinusLocal = serverNs - localNs;
            if (serverMinusLocal > windowBest_) { windowBest_ = serverMinusLocal; windowBestLocal_ = localNs; }
            estimate_ = Math.Max(estimate_, windowBest_);
            if (++windowCount_ == Window)
            {
                estimate_ = windowBest_;
                pointLocal_[nextPoint_] = windowBestLocal_;
                pointOffset_[nextPoint_] = windowBest_;
                nextPoint_ = (nextPoint_ + 1) % Points;
                pointCount_ = Math.Min(pointCount_ + 1, Points);
                if (pointCount_ >= 2)
                {
                    double meanT = 0, meanO = 0;
                    for (int i = 0; i < pointCount_; ++i) { meanT += pointLocal_[i] - pointLocal_[0]; meanO += pointOffset_[i] - pointOffset_[0]; }
                    meanT /= pointCount_;
                    meanO /= pointCount_;
                    double stt = 0, sto = 0;
                    for (int i = 0; i < pointCount_; ++i)
                    {
                        double t = (pointLocal_[i] - pointLocal_[0]) - meanT, o = (pointOffset_[i] - pointOffset_[0]) - meanO;
                        stt += t * t;
                        sto += t * o;
                    }
                    if (stt > 0) drift_ = sto / stt;
                }
                windowBest_ = long.MinValue;
                windowCount_ = 0;
            }
            return Math.Max(0, estimate_ - serverMinusLocal);
        }

        internal long? OffsetNs { get { return estimate_ == long.MinValue ? (long?)null : estimate_; } }
        internal double? Drift { get { return drift_; } }

        internal long? ServerNsAt(long localNs)
        {
            if (estimate_ == long.MinValue) return null;
            if (!drift_.HasValue || pointCount_ == 0) return localNs + estimate_;
            int newest = (nextPoint_ + Points - 1) % Points;
            return localNs + pointOffset_[newest] + (long)(drift_.Value * (localNs - pointLocal_[newest]));
        }
    }

    internal sealed class StateLink : IDisposable
    {
        private readonly Socket socket_;
        private readonly Thread receiver_, heartbeats_;
        private readonly ManualResetEvent stopping_ = new ManualResetEvent(false);
        private readonly AutoResetEvent beatSoon_ = new AutoResetEvent(false);
        private readonly int heartbeatPeriodMs_;
        private volatile bool stopped_;
        private volatile bool heartbeatsEnabled_ = true;
        private int ackWindow_;
        private long heartbeatSequence_;

        private readonly object identity_ = new object();
        private IPEndPoint server_;  // guarded by identity_
        private ulong sessionId_;    // guarded by identity_
        private byte[] key_;         // guarded by identity_

        // The stream's bookkeeping (guarded by gate_; Monitor.PulseAll on it wakes pollers).
        private readonly object gate_ = new object();
        private State latest_;
        private bool haveLatest_;
        private ulong? lastPolledTick_;
        private ulong lastSequence_, seenWindow_, staleThrough_, newestTick_;
        private ClockSync clock_ = new ClockSync();
        private long lastHeardNs_;
        private ReceiveCounters counters_;
        private ulong sessionAcceptedBase_, sessionLostBase_, acceptedAtAcknowledgement_;
        private long echoStateTimeNs_, echoReceivedAtNs_;
        private readonly List<Action<State>> taps_ = new List<Action<State>>();  // guarded by gate_

        // The callback: run on the receive thread under callbackGate_, so OnState(null) waits a
        // call in progress out.
        private readonly object callbackGate_ = new object();
        private Action<State> callback_;

        internal StateLink(IPEndPoint server, ulong sessionId, byte[] key, int heartbeatPeriodMs)
        {
            server_ = server;
            sessionId_ = sessionId;
            key_ = key;
            heartbeatPeriodMs_ = Math.Max(1, heartbeatPeriodMs);
            socket_ = new Socket(server.AddressFamily, SocketType.Dgram, ProtocolType.Udp);
            try
            {
                socket_.ReceiveBufferSize = 4 << 20;  // the kernel may grant less; AckWindowCapacity reads what it did
            }
            catch (SocketException) { }
            socket_.Bind(new IPEndPoint(server.AddressFamily == AddressFamily.InterNetworkV6 ? IPAddress.IPv6Any : IPAddress.Any, 0));
            socket_.Blocking = false;  // the receive thread waits in Poll; a read never blocks (Drain)
            receiver_ = new Thread(ReceiveLoop) { IsBackground = true, Name = "hapticd state" };
            heartbeats_ = new Thread(HeartbeatLoop) { IsBackground = true, Name = "hapticd heartbeats" };
            receiver_.Start();
            heartbeats_.Start();
        }

        internal bool HeartbeatsEnabled { set { heartbeatsEnabled_ = value; } }
        internal void SendHeartbeatSoon() { beatSoon_.Set(); }
        internal bool OnReceiveThread { get { return Thread.CurrentThread == receiver_; } }

        /// <summary>How many State datagrams the socket can hold unread (2 KiB each, as the C++
        /// SDK counts), to ask a lockstep server for as the flow-control window.</summary>
        internal uint AckWindowCapacity
        {
            get { return (uint)Math.Min(65536, Math.Max(16, socket_.ReceiveBufferSize / 2048)); }
        }
        internal uint AckWindow { set { Interlocked.Exchange(ref ackWindow_, (int)value); } }

        internal void OnState(Action<State> callback)
        {
            lock (callbackGate_) callback_ = callback;
        }

        internal void AddTap(Action<State> tap) { lock (gate_) taps_.Add(tap); }
        internal void RemoveTap(Action<State> tap) { lock (gate_) taps_.Remove(tap); }

        /// <summary>Points the link at a new session (a reconnection that opened one): the old
        /// stream's sequence, ticks and clock are forgotten; the counters stay.</summary>
        internal void Rebind(IPEndPoint server, ulong sessionId, byte[] key)
        {
            lock (identity_)
            {
                server_ = server;
                sessionId_ = sessionId;
                key_ = key;
            }
            lock (gate_)
            {
                Interlocked.Exchange(ref heartbeatSequence_, 0);
                lastSequence_ = seenWindow_ = staleThrough_ = 0;
                sessionAcceptedBase_ = counters_.Accepted;
                sessionLostBase_ = counters_.Lost;
                ForgetTicks();
            }
            SendHeartbeatSoon();
        }

        /// <summary>A stream started again after a stop is numbered from 1 again.</summary>
        internal void NewSubscription() { lock (gate_) staleThrough_ = 0; }

        /// <summary>The server's ticks start from 1 again (a lockstep Reset): what the socket
        /// holds now is the old run's; it is read, then the old run is forgotten.</summary>
        internal void RestartTicks()
        {
            Drain(false);
            lock (gate_)
            {
                staleThrough_ = lastSequence_;
                ForgetTicks();
            }
        }

        private void ForgetTicks()
        {
            newestTick_ = 0;
            haveLatest_ = false;
            lastPolledTick_ = null;
            clock_ = new ClockSync();
        }

        /// <summary>A sample that came another way (a Step reply): kept if it is the newest.</summary>
        internal void Offer(State state)
        {
            lock (gate_)
            {
                if (haveLatest_ && state.Tick <= latest_.Tick) return;
                latest_ = state;
                haveLatest_ = true;
                Monitor.PulseAll(gate_);
            }
        }

        internal bool Poll(out State state, uint timeoutMs)
        {
            return WaitFor(() => haveLatest_ && (!lastPolledTick_.HasValue || latest_.Tick > lastPolledTick_.Value), timeoutMs, out state);
        }

        internal bool WaitForTick(ulong tick, out State state, uint timeoutMs)
        {
            return WaitFor(() => haveLatest_ && latest_.Tick >= tick, timeoutMs, out state);
        }

        private bool WaitFor(Func<bool> ready, uint timeoutMs, out State state)
        {
            long deadline = SteadyClock.Ns() + timeoutMs * 1000000L;
            lock (gate_)
            {
                while (!ready())
                {
                    long left = (deadline - SteadyClock.Ns()) / 1000000L;
                    if (left <= 0 || stopped_) { state = new State(); return false; }
                    Monitor.Wait(gate_, (int)Math.Min(left + 1, int.MaxValue));
                }
                state = latest_;
                lastPolledTick_ = latest_.Tick;
                return true;
            }
        }

        internal ReceiveCounters Counters { get { lock (gate_) return counters_; } }
        internal void CountLost(ulong samples) { lock (gate_) counters_.Lost += samples; }
        internal void CountReconnect() { lock (gate_) counters_.Reconnects++; }
        internal long? ClockOffsetNs { get { lock (gate_) return clock_.OffsetNs; } }
        internal double? ClockDrift { get { lock (gate_) return clock_.Drift; } }
        internal double? ServerTimeAt(long localNs)
        {
            lock (gate_)
            {
                var ns = clock_.ServerNsAt(localNs);
                return ns.HasValue ? ns.Value * 1e-9 : (double?)null;
            }
        }
        /// <summary>When the last authenticated datagram arrived (steady ns); 0 before one.</summary>
        internal long LastHeardNs { get { lock (gate_) return lastHeardNs_; } }

        // ---- heartbeats ----

        private void HeartbeatLoop()
        {
            var handles = new WaitHandle[] { stopping_, beatSoon_ };
            for (;;)
            {
                SendHeartbeat();
                if (WaitHandle.WaitAny(handles, heartbeatPeriodMs_) == 0) return;
            }
        }

        private void SendHeartbeat()
        {
            if (!heartbeatsEnabled_ || stopped_) return;
            var header = new Wire.Header();
            byte[] key;
            IPEndPoint to;
            lock (identity_)
            {
                header.SessionId = sessionId_;
                key = key_;
                to = server_;
            }
            header.Sequence = (ulong)Interlocked.Increment(ref heartbeatSequence_);
            header.TimeNs = SteadyClock.Ns();
            var beat = new Wire.Heartbeat { ClientTimeNs = header.TimeNs };
            lock (gate_)
            {
                beat.LastStateSequence = lastSequence_;
                beat.StatesReceived = counters_.Accepted - sessionAcceptedBase_;
                beat.StatesLost = counters_.Lost > sessionLostBase_ ? counters_.Lost - sessionLostBase_ : 0;
                if (lastSequence_ > 0)
                {
                    beat.EchoStateTimeNs = echoStateTimeNs_;
                    beat.EchoHoldNs = Math.Max(0, header.TimeNs - echoReceivedAtNs_);
                }
            }
            var bytes = new byte[Wire.MaxDatagramSize];
            int n = Wire.EncodeHeartbeat(header, beat, key, bytes);
            SendTo(bytes, n, to);
        }

        private void SendTo(byte[] bytes, int length, IPEndPoint to)
        {
            // A lost datagram is made good by the next heartbeat (or, for an answer, the next challenge).
            try { socket_.SendTo(bytes, 0, length, SocketFlags.None, to); }
            catch (SocketException) { }
            catch (ObjectDisposedException) { }
        }

        // ---- receiving ----

        private void ReceiveLoop()
        {
            while (!stopped_)
            {
                try
                {
                    if (!socket_.Poll(200000, SelectMode.SelectRead)) continue;  // 200 ms: notices a stop
                }
                catch (Exception)
                {
                    return;  // closed
                }
                Drain(true);
            }
        }

        private readonly object receiveGate_ = new object();  // one reader of the socket at a time
        private readonly byte[] datagram_ = new byte[2048];

        /// <summary>Reads every datagram queued now and takes each; hands the newest State to
        /// the callback (from the receive thread only). The socket does not block: a wake-up
        /// costs poll, a recv per datagram and the recv that finds none; the source address is
        /// not asked for (the tag says who sent it; asking cost .NET an allocation per datagram).</summary>
        private void Drain(bool deliver)
        {
            State? newest = null;
            ulong accepted = 0;
            lock (receiveGate_)
            {
                long receivedAt = SteadyClock.Ns();
                try
                {
                    while (!stopped_)
                    {
                        SocketError error;
                        int n = socket_.Receive(datagram_, 0, datagram_.Length, SocketFlags.None, out error);
                        if (error != SocketError.Success) break;  // WouldBlock: all read
                        Take(datagram_, n, receivedAt, ref newest, ref accepted);
                    }
                }
                catch (SocketException) { }
                catch (ObjectDisposedException) { return; }
                if (newest.HasValue)
                {
                    lock (gate_)
                    {
                        counters_.Skipped += accepted - 1;  // passed over for the newest
                        if (!haveLatest_ || newest.Value.Tick >= latest_.Tick)
                        {
                            latest_ = newest.Value;
                            haveLatest_ = true;
                        }
                        Monitor.PulseAll(gate_);
                    }
                }
            }
            AcknowledgeIfDue();
            if (deliver && newest.HasValue)
            {
                lock (callbackGate_)
                {
                    var callback = callback_;
                    if (callback != null) callback(newest.Value);
                }
            }
        }

        private void AcknowledgeIfDue()
        {
            int window = Volatile.Read(ref ackWindow_);
            if (window == 0) return;
            bool due = false;
            lock (gate_)
            {
                if (counters_.Accepted - acceptedAtAcknowledgement_ >= (ulong)Math.Max(1, window / 4))
                {
                    acceptedAtAcknowledgement_ = counters_.Accepted;
                    due = true;
                }
            }
            if (due) SendHeartbeat();  // its last_state_sequence is the acknowledgement
        }

        private void Take(byte[] d, int length, long receivedAt, ref State? newest, ref ulong accepted)
        {
            byte[] key;
            ulong sessionId;
            IPEndPoint server;
            lock (identity_)
            {
                key = key_;
                sessionId = sessionId_;
                server = server_;
            }
            Wire.Header header;
            if (Wire.PeekHeader(d, length, out header) && header.Type == Wire.TypePathChallenge)
            {
                AnswerChallenge(d, length, key, sessionId, server);
                return;
            }
            State state;
            bool ok = Wire.DecodeState(d, length, key, out header, out state) && header.SessionId == sessionId;
            lock (gate_)
            {
                if (!ok) { counters_.Rejected++; return; }
                if (header.Sequence <= staleThrough_) { counters_.Skipped++; return; }  // of a run before a reset
                // The server numbers a subscription's States without gaps: a jump is datagrams lost,
                // one arriving late was not lost after all, one seen before is a duplicate.
                if (header.Sequence > lastSequence_)
                {
                    if (state.Tick < newestTick_)
                    {
                        // A newer datagram with an older tick: the server's ticks started again.
                        ForgetTicks();
                        staleThrough_ = header.Sequence - 1;
                        newest = null;
                    }
                    counters_.Lost += header.Sequence - lastSequence_ - 1;
                    ulong shift = header.Sequence - lastSequence_;
                    seenWindow_ = (shift >= 64 ? 0 : seenWindow_ << (int)shift) | 1UL;
                    lastSequence_ = header.Sequence;
                }
                else if (state.Tick > newestTick_)
                {
                    lastSequence_ = header.Sequence;  // a new subscription, numbered from 1 again
                    seenWindow_ = 1;
                }
                else
                {
                    ulong behind = lastSequence_ - header.Sequence;
                    if (behind >= 64) { counters_.Reordered++; return; }
                    ulong bit = 1UL << (int)behind;
                    if ((seenWindow_ & bit) != 0) { counters_.Duplicates++; return; }
                    seenWindow_ |= bit;
                    if (counters_.Lost > 0) counters_.Lost--;
                    counters_.Reordered++;
                }
                counters_.Accepted++;
                ++accepted;
                echoStateTimeNs_ = header.TimeNs;
                echoReceivedAtNs_ = receivedAt;
                state.ReceivedAtNs = receivedAt;
                lastHeardNs_ = receivedAt;
                newestTick_ = Math.Max(newestTick_, state.Tick);
                state.AgeNs = clock_.Add(header.TimeNs, receivedAt);
                if (!newest.HasValue || state.Tick >= newest.Value.Tick) newest = state;
                foreach (var tap in taps_) tap(state);
            }
        }

        /// <summary>Echoes a PathChallenge's nonce from this socket (the server sends state only
        /// to an address that proved it receives there).</summary>
        private void AnswerChallenge(byte[] d, int length, byte[] key, ulong sessionId, IPEndPoint server)
        {
            Wire.Header header;
            ulong nonce;
            if (!Wire.DecodePathChallenge(d, length, key, out header, out nonce) || header.SessionId != sessionId)
            {
                lock (gate_) counters_.Rejected++;
                return;
            }
            if (!heartbeatsEnabled_) return;  // a lost client answers nothing
            var reply = new Wire.Header { SessionId = sessionId, Sequence = (ulong)Interlocked.Increment(ref heartbeatSequence_), TimeNs = SteadyClock.Ns() };
            var bytes = new byte[Wire.MaxDatagramSize];
            SendTo(bytes, Wire.EncodePathResponse(reply, nonce, reply.TimeNs, key, bytes), server);
            lock (gate_)
            {
                counters_.ChallengesAnswered++;
                lastHeardNs_ = SteadyClock.Ns();
            }
        }

        public void Dispose()
        {
            if (stopped_) return;
            stopped_ = true;
            stopping_.Set();
            lock (gate_) Monitor.PulseAll(gate_);
            if (Thread.CurrentThread != heartbeats_) heartbeats_.Join();
            if (Thread.CurrentThread != receiver_) receiver_.Join();
            socket_.Close();
        }
    }
}
