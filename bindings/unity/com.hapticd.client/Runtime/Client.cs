// Hapticd.Client: one session with a hapticd server, over the C API (libhaptic_c). Objects and
// fields come back as handles (IDisposable: Dispose removes the item); state arrives by callback
// (on an SDK thread) or by polling; a refused call throws HapticException with the SDK's code and
// its "call: field: problem" message, and changes nothing.
//
//   using (var client = new Hapticd.Client(new Hapticd.ClientConfig { ServerAddress = "host:50051" }))
//   {
//       var wall = Hapticd.WallSpec.Default;
//       wall.Impedance = new Hapticd.Impedance(1000, 1);
//       using (var handle = client.AddWall(wall)) { ... client.PollState(out state, 100) ... }
//   }
using System;
using System.Collections.Generic;
using System.Runtime.InteropServices;
using System.Text;

// The binding's tests read the structs' sizes as the library sets them (tests/csharp).
[assembly: System.Runtime.CompilerServices.InternalsVisibleTo("ClientTests")]

namespace Hapticd
{
    /// <summary>How to reach hapticd (haptic::ClientConfig); the defaults are the C++ SDK's.</summary>
    public sealed class ClientConfig
    {
        public string ServerAddress;
        public string ClientName;
        public string Token = "";
        public string TlsCaFile = "";    // non-empty: TLS
        public string TlsCertFile = "";  // mutual TLS
        public string TlsKeyFile = "";
        public string TlsServerName = "";
        public string UdpAddress = "";
        public uint RpcTimeoutMs;
        public uint HeartbeatPeriodMs;
        public uint StateDecimation;     // state every n-th tick; 0: none
        public uint DeviceIndex;
        public bool Reconnect;
        public bool AllowPlaintextToken;
        public uint ReconnectBackoffMinMs;
        public uint ReconnectBackoffMaxMs;

        public ClientConfig()
        {
            var d = new NativeClientConfigDefaults();
            Native.haptic_client_config_init(ref d);
            ServerAddress = Marshal.PtrToStringAnsi(d.ServerAddress);
            ClientName = Marshal.PtrToStringAnsi(d.ClientName);
            RpcTimeoutMs = d.RpcTimeoutMs;
            HeartbeatPeriodMs = d.HeartbeatPeriodMs;
            StateDecimation = d.StateDecimation;
            DeviceIndex = d.DeviceIndex;
            Reconnect = d.Reconnect != 0;
            AllowPlaintextToken = d.AllowPlaintextToken != 0;
            ReconnectBackoffMinMs = d.ReconnectBackoffMinMs;
            ReconnectBackoffMaxMs = d.ReconnectBackoffMaxMs;
        }
    }

    internal static class Check
    {
        /// <summary>Throws the call's error unless it returned HAPTIC_OK (or, allowed, the timeout).</summary>
        // The calling thread's haptic_error (int32 code, 512-byte message), made once per thread and
        // kept for its life: reading it only when a call fails spares every call a string (a poll at
        // frame rate allocates nothing).
        [ThreadStatic] private static IntPtr error_;
        private const int ErrorSize = 4 + 512;

        internal static IntPtr Err
        {
            get
            {
                if (error_ == IntPtr.Zero)
                {
                    error_ = Marshal.AllocHGlobal(ErrorSize);
                    Marshal.WriteInt32(error_, 0);
                    Marshal.WriteByte(error_, 4, 0);
                }
                return error_;
            }
        }

        /// <summary>Throws the call's error (read from this thread's Err) unless it returned
        /// HAPTIC_OK or, when allowed, the timeout.</summary>
        internal static int Status(int status, bool timeoutAllowed = false)
        {
            if (status == 0 || (timeoutAllowed && status == Native.Timeout)) return status;
            string message = Marshal.PtrToStringAnsi(new IntPtr(Err.ToInt64() + 4));
            throw new HapticException((ErrorCode)status, string.IsNullOrEmpty(message) ? "error " + status : message);
        }

        internal static uint SizeOf<T>() { return (uint)Marshal.SizeOf(typeof(T)); }
    }

    /// <summary>What ObjectHandle and FieldHandle share: the library's handle of one item. Dispose
    /// (or Remove) removes the item from the server; a handle that is only collected lets go of it
    /// (it stays until the session ends).</summary>
    public abstract class ItemHandle : IDisposable
    {
        private IntPtr handle_;
        internal ItemHandle(IntPtr handle) { handle_ = handle; }
        ~ItemHandle() { if (handle_ != IntPtr.Zero) NativeRelease(handle_); }

        internal abstract ulong NativeId(IntPtr handle);
        internal abstract int NativeRemove(IntPtr handle);
        internal abstract ulong NativeRelease(IntPtr handle);

        internal IntPtr Live(string call)
        {
            if (handle_ == IntPtr.Zero) throw new HapticException(ErrorCode.FailedPrecondition, call + ": handle: removed or released already");
            return handle_;
        }

        /// <summary>The item's id on the server now; 0 once removed or released.</summary>
        public ulong Id { get { return handle_ == IntPtr.Zero ? 0 : NativeId(handle_); } }
        public bool Owned { get { return handle_ != IntPtr.Zero; } }

        /// <summary>Removes the item now; its force ramps out on the server.</summary>
        public void Remove()
        {
            if (handle_ == IntPtr.Zero) return;
            var status = NativeRemove(handle_);  // frees the handle, whatever the result
            handle_ = IntPtr.Zero;
            GC.SuppressFinalize(this);
            Check.Status(status);
        }

        /// <summary>Stops owning the item (it stays until the session ends); returns its id.</summary>
        public ulong Release()
        {
            if (handle_ == IntPtr.Zero) return 0;
            var id = NativeRelease(handle_);
            handle_ = IntPtr.Zero;
            GC.SuppressFinalize(this);
            return id;
        }

        public void Dispose() { Remove(); }
    }

    /// <summary>A registered object of any kind.</summary>
    public sealed class ObjectHandle : ItemHandle
    {
        internal ObjectHandle(IntPtr handle) : base(handle) { }
        internal override ulong NativeId(IntPtr h) { return Native.haptic_object_id(h); }
        internal override int NativeRemove(IntPtr h) { return Native.haptic_object_remove(h, Check.Err); }
        internal override ulong NativeRelease(IntPtr h) { return Native.haptic_object_release(h); }

        /// <summary>The server's stability report for the impedance as registered or last updated.</summary>
        public StabilityReport Stability
        {
            get
            {
                var r = new StabilityReport { size = Check.SizeOf<StabilityReport>() };
                Check.Status(Native.haptic_object_stability(Live("stability"), ref r, Check.Err));
                return r;
            }
        }

        public void Update(WallSpec s) { s.size = Check.SizeOf<WallSpec>(); Check.Status(Native.haptic_object_update_wall(Live("UpdateObject"), ref s, Check.Err)); }
        public void Update(SphereSpec s) { s.size = Check.SizeOf<SphereSpec>(); Check.Status(Native.haptic_object_update_sphere(Live("UpdateObject"), ref s, Check.Err)); }
        public void Update(BoxSpec s) { s.size = Check.SizeOf<BoxSpec>(); Check.Status(Native.haptic_object_update_box(Live("UpdateObject"), ref s, Check.Err)); }
        public void Update(CapsuleSpec s) { s.size = Check.SizeOf<CapsuleSpec>(); Check.Status(Native.haptic_object_update_capsule(Live("UpdateObject"), ref s, Check.Err)); }
        public void Update(TangentPlaneSpec s) { s.size = Check.SizeOf<TangentPlaneSpec>(); Check.Status(Native.haptic_object_update_tangent_plane(Live("UpdateObject"), ref s, Check.Err)); }
        public void Update(MeshSpec mesh)
        {
            var target = Live("UpdateObject");
            using (var pinned = new PinnedMesh(mesh))
            {
                var s = pinned.Spec;
                Check.Status(Native.haptic_object_update_mesh(target, ref s, Check.Err));
            }
        }
    }

    /// <summary>A registered energy field of any kind.</summary>
    public sealed class FieldHandle : ItemHandle
    {
        internal FieldHandle(IntPtr handle) : base(handle) { }
        internal override ulong NativeId(IntPtr h) { return Native.haptic_field_id(h); }
        internal override int NativeRemove(IntPtr h) { return Native.haptic_field_remove(h, Check.Err); }
        internal override ulong NativeRelease(IntPtr h) { return Native.haptic_field_release(h); }

        /// <summary>An orientation spring's stability report (Available false for other fields).</summary>
        public StabilityReport Stability
        {
            get
            {
                var r = new StabilityReport { size = Check.SizeOf<StabilityReport>() };
                Check.Status(Native.haptic_field_stability(Live("stability"), ref r, Check.Err));
                return r;
            }
        }

        public void Update(SpringFieldSpec s) { s.size = Check.SizeOf<SpringFieldSpec>(); Check.Status(Native.haptic_field_update_spring_field(Live("UpdateField"), ref s, Check.Err)); }
        public void Update(DistanceSpringSpec s) { s.size = Check.SizeOf<DistanceSpringSpec>(); Check.Status(Native.haptic_field_update_distance_spring(Live("UpdateField"), ref s, Check.Err)); }
        public void Update(PotentialFieldSpec s) { s.size = Check.SizeOf<PotentialFieldSpec>(); Check.Status(Native.haptic_field_update_potential_field(Live("UpdateField"), ref s, Check.Err)); }
        public void Update(LinearFieldSpec s) { s.size = Check.SizeOf<LinearFieldSpec>(); Check.Status(Native.haptic_field_update_linear_field(Live("UpdateField"), ref s, Check.Err)); }
        public void Update(ViscousFieldSpec s) { s.size = Check.SizeOf<ViscousFieldSpec>(); Check.Status(Native.haptic_field_update_viscous_field(Live("UpdateField"), ref s, Check.Err)); }
        public void Update(DetentFieldSpec s) { s.size = Check.SizeOf<DetentFieldSpec>(); Check.Status(Native.haptic_field_update_detent_field(Live("UpdateField"), ref s, Check.Err)); }
        public void Update(OrientationSpringSpec s) { s.size = Check.SizeOf<OrientationSpringSpec>(); Check.Status(Native.haptic_field_update_orientation_spring(Live("UpdateField"), ref s, Check.Err)); }
        public void Update(OrientationDetentSpec s) { s.size = Check.SizeOf<OrientationDetentSpec>(); Check.Status(Native.haptic_field_update_orientation_detent(Live("UpdateField"), ref s, Check.Err)); }
    }

    /// <summary>A mesh's arrays pinned for the length of one call.</summary>
    internal sealed class PinnedMesh : IDisposable
    {
        private GCHandle vertices_, indices_;
        internal NativeMeshSpec Spec;
        internal PinnedMesh(MeshSpec mesh)
        {
            if (mesh == null) throw new HapticException(ErrorCode.InvalidArgument, "CreateObject: object.mesh: is null");
            var vertices = mesh.Vertices ?? new Vec3[0];
            var indices = mesh.Indices ?? new uint[0];
            vertices_ = GCHandle.Alloc(vertices, GCHandleType.Pinned);
            indices_ = GCHandle.Alloc(indices, GCHandleType.Pinned);
            Spec = new NativeMeshSpec
            {
                size = Check.SizeOf<NativeMeshSpec>(),
                Pose = mesh.Pose,
                Vertices = vertices_.AddrOfPinnedObject(),
                VertexCount = (uint)vertices.Length,
                Indices = indices_.AddrOfPinnedObject(),
                IndexCount = (uint)indices.Length,
                Impedance = mesh.Impedance,
                Shared = mesh.Shared,
                AcrossSites = mesh.AcrossSites,
            };
        }
        public void Dispose()
        {
            if (vertices_.IsAllocated) vertices_.Free();
            if (indices_.IsAllocated) indices_.Free();
        }
    }

    /// <summary>A scene's items in unmanaged memory for one call: each spec copied with its size.</summary>
    internal sealed class NativeScene : IDisposable
    {
        internal readonly NativeSceneItem[] Items;
        private readonly List<IntPtr> blocks_ = new List<IntPtr>();
        private readonly List<PinnedMesh> meshes_ = new List<PinnedMesh>();

        internal NativeScene(IList<object> items)
        {
            Items = new NativeSceneItem[items == null ? 0 : items.Count];
            try
            {
                for (int i = 0; i < Items.Length; ++i) Items[i] = ItemOf(items[i], i);
            }
            catch
            {
                Dispose();
                throw;
            }
        }

        private IntPtr Copy<T>(T spec, uint size) where T : struct
        {
            var block = Marshal.AllocHGlobal(Marshal.SizeOf(typeof(T)));
            blocks_.Add(block);
            Marshal.StructureToPtr(spec, block, false);
            Marshal.WriteInt32(block, (int)size);  // every spec starts with its size
            return block;
        }

        private NativeSceneItem Item<T>(Kind kind, T spec) where T : struct
        {
            return new NativeSceneItem { Kind = (int)kind, Spec = Copy(spec, Check.SizeOf<T>()) };
        }

        private NativeSceneItem ItemOf(object spec, int index)
        {
            if (spec is WallSpec) return Item(Kind.Wall, (WallSpec)spec);
            if (spec is SphereSpec) return Item(Kind.Sphere, (SphereSpec)spec);
            if (spec is BoxSpec) return Item(Kind.Box, (BoxSpec)spec);
            if (spec is CapsuleSpec) return Item(Kind.Capsule, (CapsuleSpec)spec);
            if (spec is TangentPlaneSpec) return Item(Kind.TangentPlane, (TangentPlaneSpec)spec);
            if (spec is MeshSpec)
            {
                var pinned = new PinnedMesh((MeshSpec)spec);
                meshes_.Add(pinned);
                return Item(Kind.Mesh, pinned.Spec);
            }
            if (spec is SpringFieldSpec) return Item(Kind.SpringField, (SpringFieldSpec)spec);
            if (spec is DistanceSpringSpec) return Item(Kind.DistanceSpring, (DistanceSpringSpec)spec);
            if (spec is PotentialFieldSpec) return Item(Kind.PotentialField, (PotentialFieldSpec)spec);
            if (spec is LinearFieldSpec) return Item(Kind.LinearField, (LinearFieldSpec)spec);
            if (spec is ViscousFieldSpec) return Item(Kind.ViscousField, (ViscousFieldSpec)spec);
            if (spec is DetentFieldSpec) return Item(Kind.DetentField, (DetentFieldSpec)spec);
            if (spec is OrientationSpringSpec) return Item(Kind.OrientationSpring, (OrientationSpringSpec)spec);
            if (spec is OrientationDetentSpec) return Item(Kind.OrientationDetent, (OrientationDetentSpec)spec);
            throw new HapticException(ErrorCode.InvalidArgument, "ApplyScene: items[" + index + "]: " +
                (spec == null ? "is null" : spec.GetType().Name + " is not an object or field spec"));
        }

        public void Dispose()
        {
            foreach (var block in blocks_) Marshal.FreeHGlobal(block);
            blocks_.Clear();
            foreach (var mesh in meshes_) mesh.Dispose();
            meshes_.Clear();
        }
    }

    /// <summary>The handles of a scene applied whole, each list in the scene's order.</summary>
    public sealed class AppliedScene
    {
        public List<ObjectHandle> Objects = new List<ObjectHandle>();
        public List<FieldHandle> Fields = new List<FieldHandle>();
        /// <summary>The objects' stability reports, in order.</summary>
        public List<StabilityReport> Stability = new List<StabilityReport>();
    }

    /// <summary>A scene read back from the server: specs (boxed structs, MeshSpec) in id order.</summary>
    public sealed class RegisteredScene
    {
        public List<object> Objects = new List<object>();
        public List<object> Fields = new List<object>();
        public List<ulong> ObjectIds = new List<ulong>();
        public List<ulong> FieldIds = new List<ulong>();
        public List<ulong> ObjectSessions = new List<ulong>();
        public List<ulong> FieldSessions = new List<ulong>();
    }

    /// <summary>One session with a hapticd server. Methods may be called from any thread, except
    /// that Dispose must not race other calls.</summary>
    public sealed class Client : IDisposable
    {
        private IntPtr client_;
        // The delegates the library holds: kept here while it may call them, so that the garbage
        // collector cannot take them away under a running callback (never read: holding is the job).
#pragma warning disable 414
        private NativeStateCallback stateCallback_;
        private NativeEventCallback eventCallback_;
        private NativeConnectionCallback connectionCallback_;
#pragma warning restore 414
        private Action<State> onState_;
        private Action<Event> onEvent_;
        private Action<ConnectionChange> onConnection_;
        private long callbackExceptions_;

        /// <summary>Connects and opens a session. Throws HapticException (Connection,
        /// VersionMismatch, InvalidArgument naming the field, ...).</summary>
        public Client(ClientConfig config)
        {
            if (Native.haptic_c_version() != Native.HeaderVersion)
            {
                throw new HapticException(ErrorCode.VersionMismatch, "libhaptic_c is C API version " +
                    Native.haptic_c_version() + ", this binding speaks " + Native.HeaderVersion);
            }
            if (config == null) throw new HapticException(ErrorCode.InvalidArgument, "ClientConfig: config: is null");
            var c = new NativeClientConfig
            {
                size = Check.SizeOf<NativeClientConfig>(),
                ServerAddress = config.ServerAddress, ClientName = config.ClientName,
                Token = config.Token, TlsCaFile = config.TlsCaFile, TlsCertFile = config.TlsCertFile,
                TlsKeyFile = config.TlsKeyFile, TlsServerName = config.TlsServerName,
                UdpAddress = config.UdpAddress, RpcTimeoutMs = config.RpcTimeoutMs,
                HeartbeatPeriodMs = config.HeartbeatPeriodMs, StateDecimation = config.StateDecimation,
                DeviceIndex = config.DeviceIndex, Reconnect = config.Reconnect ? 1 : 0,
                AllowPlaintextToken = config.AllowPlaintextToken ? 1 : 0,
                ReconnectBackoffMinMs = config.ReconnectBackoffMinMs,
                ReconnectBackoffMaxMs = config.ReconnectBackoffMaxMs,
            };
            Check.Status(Native.haptic_client_open(ref c, out client_, Check.Err));
        }

        ~Client() { Close(false); }

        private IntPtr Live
        {
            get
            {
                if (client_ == IntPtr.Zero) throw new HapticException(ErrorCode.FailedPrecondition, "Client: closed");
                return client_;
            }
        }

        /// <summary>Ends the session; its objects and fields go with it.</summary>
        public void Dispose() { Close(true); GC.SuppressFinalize(this); }

        private void Close(bool throwOnError)
        {
            if (client_ == IntPtr.Zero) return;
            var status = Native.haptic_client_close(client_, Check.Err);
            if (status == (int)ErrorCode.FailedPrecondition)
            {
                // Called from inside one of its own callbacks: the library leaves the client open.
                if (throwOnError) Check.Status(status);
                return;
            }
            client_ = IntPtr.Zero;
            stateCallback_ = null;
            eventCallback_ = null;
            connectionCallback_ = null;
        }

        // ---- the session ----

        public DeviceInfo DeviceInfo
        {
            get
            {
                var info = new DeviceInfo { size = Check.SizeOf<DeviceInfo>() };
                Check.Status(Native.haptic_client_device_info(Live, ref info, Check.Err));
                return info;
            }
        }

        public ulong SessionId { get { return Native.haptic_client_session_id(Live); } }
        public long LeaseTimeoutMs { get { return Native.haptic_client_lease_timeout_ms(Live); } }
        public ConnectionState ConnectionState { get { return (ConnectionState)Native.haptic_client_connection_state(Live); } }

        /// <summary>Exceptions thrown by this client's callbacks (caught, so that none reaches the SDK's threads).</summary>
        public long CallbackExceptions { get { return System.Threading.Interlocked.Read(ref callbackExceptions_); } }

        // ---- state ----

        /// <summary>Waits up to timeoutMs for a sample newer than the last one returned: true and the
        /// newest in `state`, or false on timeout.</summary>
        public bool PollState(out State state, uint timeoutMs)
        {
            state = new State { size = Check.SizeOf<State>() };
            return Check.Status(Native.haptic_client_poll_state(Live, ref state, timeoutMs, Check.Err), true) == 0;
        }

        /// <summary>Waits up to timeoutMs until a sample of tick >= `tick` has arrived.</summary>
        public bool WaitForTick(ulong tick, out State state, uint timeoutMs)
        {
            state = new State { size = Check.SizeOf<State>() };
            return Check.Status(Native.haptic_client_wait_for_tick(Live, tick, ref state, timeoutMs, Check.Err), true) == 0;
        }

        public void Subscribe(uint decimation) { Check.Status(Native.haptic_client_subscribe(Live, decimation, Check.Err)); }

        /// <summary>Calls `callback` on the SDK's receive thread with each newest State (null stops
        /// it, returning once a call in progress has). Keep it short; guard what it shares.</summary>
        public void OnState(Action<State> callback)
        {
            if (callback == null)
            {
                Check.Status(Native.haptic_client_on_state(Live, null, IntPtr.Zero, Check.Err));
                stateCallback_ = null;
                onState_ = null;
                return;
            }
            onState_ = callback;
            NativeStateCallback native = (ref State state, IntPtr user) =>
            {
                try { var cb = onState_; if (cb != null) cb(state); }
                catch (Exception e) { CallbackFailed(e); }
            };
            Check.Status(Native.haptic_client_on_state(Live, native, IntPtr.Zero, Check.Err));
            stateCallback_ = native;  // the library calls the new one from now on
        }

        /// <summary>Calls `callback` on an SDK thread with each server event from now on, starting
        /// with WatchStarted (null stops it).</summary>
        public void OnEvent(Action<Event> callback)
        {
            if (callback == null)
            {
                Check.Status(Native.haptic_client_on_event(Live, null, IntPtr.Zero, Check.Err));
                eventCallback_ = null;
                onEvent_ = null;
                return;
            }
            onEvent_ = callback;
            NativeEventCallback native = (ref NativeEvent e, IntPtr user) =>
            {
                try
                {
                    var cb = onEvent_;
                    if (cb != null)
                    {
                        cb(new Event { Kind = (EventKind)e.Kind, SessionId = e.SessionId, ItemId = e.ItemId,
                                       ServerTime = e.ServerTime, Message = Marshal.PtrToStringAnsi(e.Message) ?? "" });
                    }
                }
                catch (Exception x) { CallbackFailed(x); }
            };
            Check.Status(Native.haptic_client_on_event(Live, native, IntPtr.Zero, Check.Err));
            eventCallback_ = native;
        }

        /// <summary>Calls `callback` on the SDK's supervisor thread when the connection is lost and
        /// when it resumes (null stops it).</summary>
        public void OnConnection(Action<ConnectionChange> callback)
        {
            if (callback == null)
            {
                Check.Status(Native.haptic_client_on_connection(Live, null, IntPtr.Zero, Check.Err));
                connectionCallback_ = null;
                onConnection_ = null;
                return;
            }
            onConnection_ = callback;
            NativeConnectionCallback native = (ref NativeConnectionChange c, IntPtr user) =>
            {
                try
                {
                    var cb = onConnection_;
                    if (cb != null)
                    {
                        cb(new ConnectionChange { State = (ConnectionState)c.State, SessionId = c.SessionId,
                                                  NewSession = c.NewSession != 0, ItemsNotRestored = c.ItemsNotRestored,
                                                  OutageMs = c.OutageMs, Reason = Marshal.PtrToStringAnsi(c.Reason) ?? "" });
                    }
                }
                catch (Exception x) { CallbackFailed(x); }
            };
            Check.Status(Native.haptic_client_on_connection(Live, native, IntPtr.Zero, Check.Err));
            connectionCallback_ = native;
        }

        private void CallbackFailed(Exception e)
        {
            if (System.Threading.Interlocked.Increment(ref callbackExceptions_) == 1)
            {
                Console.Error.WriteLine("hapticd: a callback threw (counted in Client.CallbackExceptions): " + e);
            }
        }

        public ReceiveCounters ReceiveCounters
        {
            get
            {
                var c = new ReceiveCounters { size = Check.SizeOf<ReceiveCounters>() };
                Check.Status(Native.haptic_client_receive_counters(Live, ref c, Check.Err));
                return c;
            }
        }

        public void SetHeartbeatsEnabled(bool enabled)
        {
            Check.Status(Native.haptic_client_set_heartbeats_enabled(Live, enabled ? 1 : 0, Check.Err));
        }

        /// <summary>The steady clock's now (ns), the clock of State's local times.</summary>
        public static long SteadyClockNs() { return Native.haptic_steady_clock_ns(); }

        /// <summary>The server's time (s) at local steady-clock time `localNs`, or null before any sample.</summary>
        public double? ServerTimeAt(long localNs)
        {
            double t;
            return Native.haptic_client_server_time_at(Live, localNs, out t) != 0 ? t : (double?)null;
        }

        /// <summary>The server's time now (s), or null before any sample: a frame's time for Motion.</summary>
        public double? ServerTimeNow() { return ServerTimeAt(SteadyClockNs()); }

        public long? ClockOffsetNs { get { long o; return Native.haptic_client_clock_offset_ns(Live, out o) != 0 ? o : (long?)null; } }
        public double? ClockDrift { get { double d; return Native.haptic_client_clock_drift(Live, out d) != 0 ? d : (double?)null; } }

        // ---- objects and fields ----

        public ObjectHandle AddWall(WallSpec s) { IntPtr h; s.size = Check.SizeOf<WallSpec>(); Check.Status(Native.haptic_client_add_wall(Live, ref s, out h, Check.Err)); return new ObjectHandle(h); }
        public ObjectHandle AddSphere(SphereSpec s) { IntPtr h; s.size = Check.SizeOf<SphereSpec>(); Check.Status(Native.haptic_client_add_sphere(Live, ref s, out h, Check.Err)); return new ObjectHandle(h); }
        public ObjectHandle AddBox(BoxSpec s) { IntPtr h; s.size = Check.SizeOf<BoxSpec>(); Check.Status(Native.haptic_client_add_box(Live, ref s, out h, Check.Err)); return new ObjectHandle(h); }
        public ObjectHandle AddCapsule(CapsuleSpec s) { IntPtr h; s.size = Check.SizeOf<CapsuleSpec>(); Check.Status(Native.haptic_client_add_capsule(Live, ref s, out h, Check.Err)); return new ObjectHandle(h); }
        public ObjectHandle AddTangentPlane(TangentPlaneSpec s) { IntPtr h; s.size = Check.SizeOf<TangentPlaneSpec>(); Check.Status(Native.haptic_client_add_tangent_plane(Live, ref s, out h, Check.Err)); return new ObjectHandle(h); }
        public ObjectHandle AddMesh(MeshSpec mesh)
        {
            var client = Live;
            using (var pinned = new PinnedMesh(mesh))
            { IntPtr h;
                var s = pinned.Spec;
                Check.Status(Native.haptic_client_add_mesh(client, ref s, out h, Check.Err));
                return new ObjectHandle(h);
            }
        }

        public FieldHandle AddField(SpringFieldSpec s) { IntPtr h; s.size = Check.SizeOf<SpringFieldSpec>(); Check.Status(Native.haptic_client_add_spring_field(Live, ref s, out h, Check.Err)); return new FieldHandle(h); }
        public FieldHandle AddField(DistanceSpringSpec s) { IntPtr h; s.size = Check.SizeOf<DistanceSpringSpec>(); Check.Status(Native.haptic_client_add_distance_spring(Live, ref s, out h, Check.Err)); return new FieldHandle(h); }
        public FieldHandle AddField(PotentialFieldSpec s) { IntPtr h; s.size = Check.SizeOf<PotentialFieldSpec>(); Check.Status(Native.haptic_client_add_potential_field(Live, ref s, out h, Check.Err)); return new FieldHandle(h); }
        public FieldHandle AddField(LinearFieldSpec s) { IntPtr h; s.size = Check.SizeOf<LinearFieldSpec>(); Check.Status(Native.haptic_client_add_linear_field(Live, ref s, out h, Check.Err)); return new FieldHandle(h); }
        public FieldHandle AddField(ViscousFieldSpec s) { IntPtr h; s.size = Check.SizeOf<ViscousFieldSpec>(); Check.Status(Native.haptic_client_add_viscous_field(Live, ref s, out h, Check.Err)); return new FieldHandle(h); }
        public FieldHandle AddField(DetentFieldSpec s) { IntPtr h; s.size = Check.SizeOf<DetentFieldSpec>(); Check.Status(Native.haptic_client_add_detent_field(Live, ref s, out h, Check.Err)); return new FieldHandle(h); }
        public FieldHandle AddField(OrientationSpringSpec s) { IntPtr h; s.size = Check.SizeOf<OrientationSpringSpec>(); Check.Status(Native.haptic_client_add_orientation_spring(Live, ref s, out h, Check.Err)); return new FieldHandle(h); }
        public FieldHandle AddField(OrientationDetentSpec s) { IntPtr h; s.size = Check.SizeOf<OrientationDetentSpec>(); Check.Status(Native.haptic_client_add_orientation_detent(Live, ref s, out h, Check.Err)); return new FieldHandle(h); }

        // ---- scenes ----

        /// <summary>Replaces this session's whole scene with `items` (object and field specs in any
        /// order); all or nothing. Handles from earlier calls go stale.</summary>
        public AppliedScene ApplyScene(IList<object> items)
        {
            var client = Live;
            using (var scene = new NativeScene(items))
            {
                IntPtr applied;
                Check.Status(Native.haptic_client_apply_scene(client, scene.Items, (uint)scene.Items.Length, out applied, Check.Err));
                return TakeAll(applied);
            }
        }

        /// <summary>The same from a scene file (protobuf JSON, as hapticd --scene reads).</summary>
        public AppliedScene ApplySceneFile(string path)
        {
            IntPtr applied;
            Check.Status(Native.haptic_client_apply_scene_file(Live, path, out applied, Check.Err));
            return TakeAll(applied);
        }

        private static AppliedScene TakeAll(IntPtr applied)
        {
            var result = new AppliedScene();
            try
            {
                uint objects, fields;
                Native.haptic_applied_scene_counts(applied, out objects, out fields);
                for (uint i = 0; i < objects; ++i)
                {
                    result.Objects.Add(new ObjectHandle(Native.haptic_applied_scene_take_object(applied, i)));
                    var r = new StabilityReport { size = Check.SizeOf<StabilityReport>() };
                    Check.Status(Native.haptic_applied_scene_stability(applied, i, ref r, Check.Err));
                    result.Stability.Add(r);
                }
                for (uint i = 0; i < fields; ++i) result.Fields.Add(new FieldHandle(Native.haptic_applied_scene_take_field(applied, i)));
            }
            finally
            {
                Native.haptic_applied_scene_free(applied);
            }
            return result;
        }

        /// <summary>`items` as a scene file (the JSON ApplySceneFile reads).</summary>
        public static string SceneJson(IList<object> items)
        {
            using (var scene = new NativeScene(items))
            {
                UIntPtr length;
                Check.Status(Native.haptic_scene_json(scene.Items, (uint)scene.Items.Length, null, UIntPtr.Zero, out length, Check.Err));
                var buffer = new byte[(int)length.ToUInt64() + 1];
                Check.Status(Native.haptic_scene_json(scene.Items, (uint)scene.Items.Length, buffer, (UIntPtr)buffer.Length, out length, Check.Err));
                return Encoding.UTF8.GetString(buffer, 0, (int)length.ToUInt64());
            }
        }

        /// <summary>This session's objects and fields as the server holds them; with allSessions, everyone's.</summary>
        public RegisteredScene Scene(bool allSessions = false)
        {
            IntPtr scene;
            Check.Status(Native.haptic_client_scene(Live, allSessions ? 1 : 0, out scene, Check.Err));
            var result = new RegisteredScene();
            try
            {
                uint objects, fields;
                Native.haptic_registered_scene_counts(scene, out objects, out fields);
                for (uint i = 0; i < objects; ++i)
                {
                    var entry = new NativeSceneEntry { size = Check.SizeOf<NativeSceneEntry>() };
                    Check.Status(Native.haptic_registered_scene_object(scene, i, ref entry, Check.Err));
                    result.Objects.Add(ReadSpec(scene, i, (Kind)entry.Kind, true));
                    result.ObjectIds.Add(entry.Id);
                    result.ObjectSessions.Add(entry.SessionId);
                }
                for (uint i = 0; i < fields; ++i)
                {
                    var entry = new NativeSceneEntry { size = Check.SizeOf<NativeSceneEntry>() };
                    Check.Status(Native.haptic_registered_scene_field(scene, i, ref entry, Check.Err));
                    result.Fields.Add(ReadSpec(scene, i, (Kind)entry.Kind, false));
                    result.FieldIds.Add(entry.Id);
                    result.FieldSessions.Add(entry.SessionId);
                }
            }
            finally
            {
                Native.haptic_registered_scene_free(scene);
            }
            return result;
        }

        private static object ReadSpec(IntPtr scene, uint index, Kind kind, bool isObject)
        {
            switch (kind)
            {
                case Kind.Wall: return Read<WallSpec>(scene, index, isObject);
                case Kind.Sphere: return Read<SphereSpec>(scene, index, isObject);
                case Kind.Box: return Read<BoxSpec>(scene, index, isObject);
                case Kind.Capsule: return Read<CapsuleSpec>(scene, index, isObject);
                case Kind.TangentPlane: return Read<TangentPlaneSpec>(scene, index, isObject);
                case Kind.Mesh:
                {
                    var n = Read<NativeMeshSpec>(scene, index, isObject);  // arrays point into the scene
                    var mesh = new MeshSpec { Pose = n.Pose, Impedance = n.Impedance, Shared = n.Shared, AcrossSites = n.AcrossSites };
                    mesh.Vertices = new Vec3[n.VertexCount];
                    var stride = Marshal.SizeOf(typeof(Vec3));
                    for (int v = 0; v < mesh.Vertices.Length; ++v)
                    {
                        mesh.Vertices[v] = (Vec3)Marshal.PtrToStructure(new IntPtr(n.Vertices.ToInt64() + v * stride), typeof(Vec3));
                    }
                    var indices = new int[n.IndexCount];
                    if (indices.Length > 0) Marshal.Copy(n.Indices, indices, 0, indices.Length);
                    mesh.Indices = Array.ConvertAll(indices, i => (uint)i);
                    return mesh;
                }
                case Kind.SpringField: return Read<SpringFieldSpec>(scene, index, isObject);
                case Kind.DistanceSpring: return Read<DistanceSpringSpec>(scene, index, isObject);
                case Kind.PotentialField: return Read<PotentialFieldSpec>(scene, index, isObject);
                case Kind.LinearField: return Read<LinearFieldSpec>(scene, index, isObject);
                case Kind.ViscousField: return Read<ViscousFieldSpec>(scene, index, isObject);
                case Kind.DetentField: return Read<DetentFieldSpec>(scene, index, isObject);
                case Kind.OrientationSpring: return Read<OrientationSpringSpec>(scene, index, isObject);
                case Kind.OrientationDetent: return Read<OrientationDetentSpec>(scene, index, isObject);
            }
            throw new HapticException(ErrorCode.Internal, "GetScene: kind: " + (int)kind + " is not known to this binding");
        }

        private static T Read<T>(IntPtr scene, uint index, bool isObject) where T : struct
        {
            var block = Marshal.AllocHGlobal(Marshal.SizeOf(typeof(T)));
            try
            {
                for (int i = 0; i < Marshal.SizeOf(typeof(T)); ++i) Marshal.WriteByte(block, i, 0);
                Marshal.WriteInt32(block, (int)Check.SizeOf<T>());
                Check.Status(isObject ? Native.haptic_registered_scene_object_spec(scene, index, block, Check.Err)
                                      : Native.haptic_registered_scene_field_spec(scene, index, block, Check.Err));
                return (T)Marshal.PtrToStructure(block, typeof(T));
            }
            finally
            {
                Marshal.FreeHGlobal(block);
            }
        }

        public ItemEnergy[] SceneEnergy()
        {
            uint count;
            Check.Status(Native.haptic_client_scene_energy(Live, null, 0, out count, Check.Err));
            var items = new ItemEnergy[count];
            Check.Status(Native.haptic_client_scene_energy(Live, items, count, out count, Check.Err));
            return count < items.Length ? SubArray(items, count) : items;
        }

        public ObjectState[] ObjectStates()
        {
            uint count;
            Check.Status(Native.haptic_client_object_states(Live, null, 0, out count, Check.Err));
            var states = new ObjectState[count];
            Check.Status(Native.haptic_client_object_states(Live, states, count, out count, Check.Err));
            return count < states.Length ? SubArray(states, count) : states;
        }

        private static T[] SubArray<T>(T[] items, uint count)
        {
            var result = new T[count];
            Array.Copy(items, result, count);
            return result;
        }

        // ---- the simulated operator, lockstep ----

        public void SetOperator(OperatorInput input)
        {
            if (input == null) throw new HapticException(ErrorCode.InvalidArgument, "SetOperator: input: is null");
            var samples = input.ProfileSamples ?? new Vec3[0];
            var pinned = GCHandle.Alloc(samples, GCHandleType.Pinned);
            try
            {
                var n = new NativeOperatorInput
                {
                    size = Check.SizeOf<NativeOperatorInput>(), Mode = (int)input.Mode, Target = input.Target,
                    Stiffness = input.Stiffness, Damping = input.Damping, Mass = input.Mass, Grip = (int)input.Grip,
                    PathShape = (int)input.PathShape, PathEnd = input.PathEnd, PathDurationS = input.PathDurationS,
                    PathAmplitude = input.PathAmplitude, PathFrequencyHz = input.PathFrequencyHz, Force = input.Force,
                    ProfileShape = (int)input.ProfileShape, ProfileRepeat = input.ProfileRepeat ? 1 : 0,
                    ProfileStartS = input.ProfileStartS, ProfileRiseS = input.ProfileRiseS,
                    ProfileFrequencyHz = input.ProfileFrequencyHz, ProfileOffset = input.ProfileOffset,
                    ProfileSamples = pinned.AddrOfPinnedObject(), ProfileSampleCount = (uint)samples.Length,
                    ProfileSamplePeriodS = input.ProfileSamplePeriodS,
                };
                Check.Status(Native.haptic_client_set_operator(Live, ref n, Check.Err));
            }
            finally
            {
                pinned.Free();
            }
        }

        /// <summary>Lockstep servers only: runs `ticks` ticks; returns the last one's index.</summary>
        public ulong Step(uint ticks)
        {
            ulong last;
            Check.Status(Native.haptic_client_step(Live, ticks, out last, Check.Err));
            return last;
        }

        /// <summary>Lockstep servers with simulated devices only: puts the server back as it started.</summary>
        public void Reset() { Check.Status(Native.haptic_client_reset(Live, Check.Err)); }

        // ---- administration ----

        public Stats Stats()
        {
            var counters = new StatsCounters { size = Check.SizeOf<StatsCounters>() };
            Check.Status(Native.haptic_client_stats(Live, ref counters, null, 0, null, 0, Check.Err));
            var stats = new Stats
            {
                Clients = new StreamStats[counters.ClientCount + 4],  // room for sessions opened meanwhile
                Couplings = new CouplingStats[counters.CouplingCount + 4],
            };
            Check.Status(Native.haptic_client_stats(Live, ref counters, stats.Clients, (uint)stats.Clients.Length,
                                                    stats.Couplings, (uint)stats.Couplings.Length, Check.Err));
            stats.Counters = counters;
            stats.Clients = SubArray(stats.Clients, Math.Min(counters.ClientCount, (uint)stats.Clients.Length));
            stats.Couplings = SubArray(stats.Couplings, Math.Min(counters.CouplingCount, (uint)stats.Couplings.Length));
            return stats;
        }

        public SessionSummary[] Sessions()
        {
            uint count;
            Check.Status(Native.haptic_client_sessions(Live, null, 0, out count, Check.Err));
            var sessions = new SessionSummary[count + 4];
            Check.Status(Native.haptic_client_sessions(Live, sessions, (uint)sessions.Length, out count, Check.Err));
            return SubArray(sessions, Math.Min(count, (uint)sessions.Length));
        }

        public void KickSession(ulong sessionId, string reason = "")
        {
            Check.Status(Native.haptic_client_kick_session(Live, sessionId, reason ?? "", Check.Err));
        }

        public RecordingStatus StartRecording(string name)
        {
            var status = new RecordingStatus { size = Check.SizeOf<RecordingStatus>() };
            Check.Status(Native.haptic_client_start_recording(Live, name, ref status, Check.Err));
            return status;
        }

        /// <summary>Starts recording what this client receives into a file (docs/recorder.md).
        /// Refused (HapticException, InvalidArgument naming the field) for a bad path or an
        /// existing file; nothing is left behind then.</summary>
        public Recorder Record(RecorderOptions options)
        {
            if (options == null) throw new HapticException(ErrorCode.InvalidArgument, "record: options: is null");
            var n = new NativeRecorderOptions
            {
                size = Check.SizeOf<NativeRecorderOptions>(), Path = options.Path ?? "", Format = (int)options.Format,
                Events = options.Events ? 1 : 0, Overwrite = options.Overwrite ? 1 : 0, QueueCapacity = options.QueueCapacity,
            };
            IntPtr recorder;
            Check.Status(Native.haptic_client_record(Live, ref n, out recorder, Check.Err));
            return new Recorder(recorder);
        }

        public RecordingStatus StopRecording()
        {
            var status = new RecordingStatus { size = Check.SizeOf<RecordingStatus>() };
            Check.Status(Native.haptic_client_stop_recording(Live, ref status, Check.Err));
            return status;
        }
    }

    /// <summary>Records what a client receives into CSV or HDF5 (docs/recorder.md): every State it
    /// accepts, and the server's events. Dispose (or Close) drains, flushes and closes the file.</summary>
    public sealed class Recorder : IDisposable
    {
        private IntPtr recorder_;
        private RecorderStats totals_;
        public string Path { get; private set; }
        public string EventsPath { get; private set; }

        internal Recorder(IntPtr recorder)
        {
            recorder_ = recorder;
            Path = Marshal.PtrToStringAnsi(Native.haptic_recorder_path(recorder)) ?? "";
            EventsPath = Marshal.PtrToStringAnsi(Native.haptic_recorder_events_path(recorder)) ?? "";
        }
        // A finalizer must not throw (it would end the process); Close only reports a bad size.
        ~Recorder() { try { Close(); } catch (HapticException) { } }

        public bool Recording { get { return recorder_ != IntPtr.Zero; } }

        /// <summary>The totals so far; after Close, the final ones.</summary>
        public RecorderStats Stats
        {
            get
            {
                if (recorder_ == IntPtr.Zero) return totals_;
                var stats = new RecorderStats { size = Check.SizeOf<RecorderStats>() };
                Check.Status(Native.haptic_recorder_get_stats(recorder_, ref stats, Check.Err));
                return stats;
            }
        }

        /// <summary>Stops recording, writes what is queued, flushes and closes the file(s); the
        /// totals (again on later calls). A failed write is in the totals.</summary>
        public RecorderStats Close()
        {
            if (recorder_ == IntPtr.Zero) return totals_;
            var totals = new RecorderStats { size = Check.SizeOf<RecorderStats>() };
            var status = Native.haptic_recorder_close(recorder_, ref totals, Check.Err);
            recorder_ = IntPtr.Zero;
            totals_ = totals;
            GC.SuppressFinalize(this);
            Check.Status(status);
            return totals_;
        }

        public void Dispose() { Close(); }
    }

    /// <summary>Between and beyond the samples: the tool's position at a server time a frame needs.</summary>
    public static class Motion
    {
        /// <summary>The position at server time t between samples a and b (cubic Hermite).</summary>
        public static Vec3 Interpolate(State a, State b, double t) { return Native.haptic_interpolate_position(ref a, ref b, t); }
        /// <summary>The position at server time t after `latest`, with the acceleration the two newest imply.</summary>
        public static Vec3 Predict(State previous, State latest, double t) { return Native.haptic_predict_position(ref previous, ref latest, t); }
    }
}
