// Moves its GameObject with the haptic tool at frame rate: opens a session with hapticd, takes
// the state stream on the SDK's receive thread (keeping the two newest samples), and in each
// frame's Update places the transform where the tool is at the frame's server time, interpolated
// between the samples (a little behind, always between two real samples) or predicted past the
// newest (no added lag, a small error when the hand accelerates). docs/unity.md.
//
// A connection it cannot make (for any reason: refused, no server, no HTTP face, TLS) is reported
// in the console and leaves the scene running without the tool; one lost, resumed or ended later
// is reported from the next frame's Update, on Unity's main thread.
//
// Frames: hapticd's W is right-handed with z up (as every simulated device and example uses it);
// Unity's world is left-handed with y up. W (x, y, z) maps to Unity (x, z, y) times `unitsPerMeter`.
using System;
using System.Collections.Generic;
using UnityEngine;

namespace Hapticd.Unity
{
    public class HapticToolFollower : MonoBehaviour
    {
        public enum Smoothing { Interpolate, Predict }

        [Tooltip("hapticd's gRPC address, host:port")]
        public string serverAddress = "127.0.0.1:8081";  // hapticd's HTTP face (hapticd --http-api 8081)
        [Tooltip("Shown in the server's log")]
        public string clientName = "unity";
        [Tooltip("The server's device port (0: its configured device)")]
        public int deviceIndex = 0;
        [Tooltip("Interpolate between the two newest samples, or predict past the newest")]
        public Smoothing smoothing = Smoothing.Interpolate;
        [Tooltip("Interpolate: how far behind the server's now to render, in seconds (at least one sample period)")]
        public float interpolationDelay = 0.002f;
        [Tooltip("Unity units per meter of the device's workspace")]
        public float unitsPerMeter = 10f;

        private Client client_;
        private readonly object gate_ = new object();
        private State previous_, latest_;
        private int samples_;
        private readonly Queue<ConnectionChange> connectionChanges_ = new Queue<ConnectionChange>();  // under gate_
        private bool updateFailed_;

        /// <summary>The session, once enabled (null before, or if the server could not be reached).</summary>
        public Client Client { get { return client_; } }

        private void OnEnable()
        {
            updateFailed_ = false;
            try
            {
                client_ = new Client(new ClientConfig { ServerAddress = serverAddress, ClientName = clientName, DeviceIndex = (uint)deviceIndex });
                client_.OnConnection(OnConnectionChange);
                client_.OnState(OnSample);
            }
            catch (Exception e)
            {
                // Not only HapticException: any failure (a certificate file unreadable, a socket
                // the platform refuses) must not take the scene down with it.
                Debug.LogError("hapticd: cannot connect to " + serverAddress + " (" + Describe(e) + "); the tool will not move");
                if (client_ != null) client_.Dispose();
                client_ = null;
            }
        }

        private void OnDisable()
        {
            if (client_ == null) return;
            client_.OnState(null);
            client_.OnConnection(null);
            client_.Dispose();
            client_ = null;
            lock (gate_) samples_ = 0;
        }

        // On the SDK's receive thread: keep the two newest samples, nothing else.
        private void OnSample(State state)
        {
            lock (gate_)
            {
                previous_ = latest_;
                latest_ = state;
                samples_++;
            }
        }

        // On the SDK's thread: kept for Update to report on the main thread.
        private void OnConnectionChange(ConnectionChange change)
        {
            lock (gate_) connectionChanges_.Enqueue(change);
        }

        private void Update()
        {
            if (client_ == null) return;
            ReportConnectionChanges();
            try
            {
                double? now = client_.ServerTimeNow();
                if (!now.HasValue) return;
                PlaceAt(smoothing == Smoothing.Interpolate ? now.Value - interpolationDelay : now.Value);
                updateFailed_ = false;
            }
            catch (Exception e)
            {
                // Once per run of failures: a frame's error must not flood the console every frame.
                if (!updateFailed_) Debug.LogError("hapticd: cannot place the tool (" + Describe(e) + ")");
                updateFailed_ = true;
            }
        }

        private void ReportConnectionChanges()
        {
            while (true)
            {
                ConnectionChange change;
                lock (gate_)
                {
                    if (connectionChanges_.Count == 0) return;
                    change = connectionChanges_.Dequeue();
                }
                string reason = string.IsNullOrEmpty(change.Reason) ? "" : ": " + change.Reason;
                switch (change.State)
                {
                    case ConnectionState.Lost:
                        Debug.LogWarning("hapticd: the connection to " + serverAddress + " is lost" + reason + "; reconnecting, the tool holds still");
                        break;
                    case ConnectionState.Resumed:
                        Debug.Log("hapticd: the connection to " + serverAddress + " is back after " + change.OutageMs + " ms" +
                                  (change.NewSession ? " in a new session (" + change.ItemsNotRestored + " items not restored)" : ""));
                        break;
                    case ConnectionState.Ended:
                        Debug.LogError("hapticd: the session with " + serverAddress + " has ended" + reason);
                        break;
                }
            }
        }

        private static string Describe(Exception e)
        {
            var haptic = e as HapticException;
            return haptic != null ? haptic.Message : e.GetType().Name + ": " + e.Message;
        }

        /// <summary>Places the transform where the tool is at server time `serverTime` (s); false
        /// before two samples have arrived.</summary>
        public bool PlaceAt(double serverTime)
        {
            State a, b;
            lock (gate_)
            {
                if (samples_ < 2) return false;
                a = previous_;
                b = latest_;
            }
            Vec3 p = smoothing == Smoothing.Interpolate ? Motion.Interpolate(a, b, Math.Min(serverTime, b.ServerTime))
                                                        : Motion.Predict(a, b, serverTime);
            transform.position = ToUnity(p) * unitsPerMeter;
            return true;
        }

        /// <summary>A position in W (m) as a Unity vector (axes only; no scale).</summary>
        public static Vector3 ToUnity(Vec3 p) { return new Vector3((float)p.X, (float)p.Z, (float)p.Y); }
    }
}
