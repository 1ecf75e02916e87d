// Moves its GameObject with the haptic tool at frame rate: opens a session with hapticd, takes
// the state stream on the SDK's receive thread (keeping the two newest samples), and in each
// frame's Update places the transform where the tool is at the frame's server time, interpolated
// between the samples (a little behind, always between two real samples) or predicted past the
// newest (no added lag, a small error when the hand accelerates). docs/unity.md.
//
// Frames: hapticd's W is right-handed with z up (as every simulated device and example uses it);
// Unity's world is left-handed with y up. W (x, y, z) maps to Unity (x, z, y) times `unitsPerMeter`.
using System;
using UnityEngine;

namespace Hapticd.Unity
{
    public class HapticToolFollower : MonoBehaviour
    {
        public enum Smoothing { Interpolate, Predict }

        [Tooltip("hapticd's gRPC address, host:port")]
        public string serverAddress = "127.0.0.1:50051";
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

        /// <summary>The session, once enabled (null before, or if the server could not be reached).</summary>
        public Client Client { get { return client_; } }

        private void OnEnable()
        {
            try
            {
                client_ = new Client(new ClientConfig { ServerAddress = serverAddress, ClientName = clientName, DeviceIndex = (uint)deviceIndex });
                client_.OnState(OnSample);
            }
            catch (HapticException e)
            {
                Debug.LogError("hapticd: " + e.Message);
                client_ = null;
            }
        }

        private void OnDisable()
        {
            if (client_ == null) return;
            client_.OnState(null);
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

        private void Update()
        {
            if (client_ == null) return;
            double? now = client_.ServerTimeNow();
            if (!now.HasValue) return;
            PlaceAt(smoothing == Smoothing.Interpolate ? now.Value - interpolationDelay : now.Value);
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
