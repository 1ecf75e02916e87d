// P/Invoke declarations of the C API (haptic/haptic_c.h, version 1) in libhaptic_c. Internal:
// applications use Client and its handles. Every function that can fail returns a haptic_status
// and fills a haptic_error (Check.Err, a buffer of the calling thread's); Client turns those into
// HapticException.
using System;
using System.Runtime.InteropServices;

namespace Hapticd
{
    [StructLayout(LayoutKind.Sequential)]
    internal struct NativeClientConfig
    {
        public uint size;
        [MarshalAs(UnmanagedType.LPStr)] public string ServerAddress;
        [MarshalAs(UnmanagedType.LPStr)] public string ClientName;
        [MarshalAs(UnmanagedType.LPStr)] public string Token;
        [MarshalAs(UnmanagedType.LPStr)] public string TlsCaFile;
        [MarshalAs(UnmanagedType.LPStr)] public string TlsCertFile;
        [MarshalAs(UnmanagedType.LPStr)] public string TlsKeyFile;
        [MarshalAs(UnmanagedType.LPStr)] public string TlsServerName;
        [MarshalAs(UnmanagedType.LPStr)] public string UdpAddress;
        public uint RpcTimeoutMs;
        public uint HeartbeatPeriodMs;
        public uint StateDecimation;
        public uint DeviceIndex;
        public int Reconnect;
        public int AllowPlaintextToken;
        public uint ReconnectBackoffMinMs;
        public uint ReconnectBackoffMaxMs;
    }

    /// <summary>The config as the library's init fills it, with its strings as IntPtr (read once).</summary>
    [StructLayout(LayoutKind.Sequential)]
    internal struct NativeClientConfigDefaults
    {
        public uint size;
        public IntPtr ServerAddress, ClientName, Token, TlsCaFile, TlsCertFile, TlsKeyFile, TlsServerName, UdpAddress;
        public uint RpcTimeoutMs, HeartbeatPeriodMs, StateDecimation, DeviceIndex;
        public int Reconnect, AllowPlaintextToken;
        public uint ReconnectBackoffMinMs, ReconnectBackoffMaxMs;
    }

    [StructLayout(LayoutKind.Sequential)]
    internal struct NativeMeshSpec
    {
        public uint size;
        public Pose Pose;
        public IntPtr Vertices;
        public uint VertexCount;
        public uint IndexCount;
        public IntPtr Indices;
        public Impedance Impedance;
        [MarshalAs(UnmanagedType.Bool)] public bool Shared;
        [MarshalAs(UnmanagedType.Bool)] public bool AcrossSites;
    }

    [StructLayout(LayoutKind.Sequential)]
    internal struct NativeSceneItem
    {
        public int Kind;
        public IntPtr Spec;
    }

    [StructLayout(LayoutKind.Sequential)]
    internal struct NativeSceneEntry
    {
        public uint size;
        public int Kind;
        public ulong Id;
        public ulong SessionId;
    }

    [StructLayout(LayoutKind.Sequential)]
    internal struct NativeEvent
    {
        public uint size;
        public int Kind;
        public ulong SessionId;
        public ulong ItemId;
        public double ServerTime;
        public IntPtr Message;
    }

    [StructLayout(LayoutKind.Sequential)]
    internal struct NativeConnectionChange
    {
        public uint size;
        public int State;
        public ulong SessionId;
        public int NewSession;
        public uint ItemsNotRestored;
        public long OutageMs;
        public IntPtr Reason;
    }

    [StructLayout(LayoutKind.Sequential)]
    internal struct NativeOperatorInput
    {
        public uint size;
        public int Mode;
        public Vec3 Target;
        public double Stiffness, Damping, Mass;
        public int Grip, PathShape;
        public Vec3 PathEnd;
        public double PathDurationS;
        public Vec3 PathAmplitude;
        public double PathFrequencyHz;
        public Vec3 Force;
        public int ProfileShape, ProfileRepeat;
        public double ProfileStartS, ProfileRiseS, ProfileFrequencyHz;
        public Vec3 ProfileOffset;
        public IntPtr ProfileSamples;
        public uint ProfileSampleCount;
        public double ProfileSamplePeriodS;
    }

    [StructLayout(LayoutKind.Sequential)]
    internal struct NativeRecorderOptions
    {
        public uint size;
        [MarshalAs(UnmanagedType.LPStr)] public string Path;
        public int Format;
        public int Events;
        public int Overwrite;
        public ulong QueueCapacity;
    }

    internal enum Kind : int
    {
        Wall = 1, Sphere = 2, Box = 3, Capsule = 4, TangentPlane = 5, Mesh = 6,
        SpringField = 101, DistanceSpring = 102, PotentialField = 103, LinearField = 104,
        ViscousField = 105, DetentField = 106, OrientationSpring = 107, OrientationDetent = 108
    }

    [UnmanagedFunctionPointer(CallingConvention.Cdecl)]
    internal delegate void NativeStateCallback(ref State state, IntPtr userData);
    [UnmanagedFunctionPointer(CallingConvention.Cdecl)]
    internal delegate void NativeEventCallback(ref NativeEvent e, IntPtr userData);
    [UnmanagedFunctionPointer(CallingConvention.Cdecl)]
    internal delegate void NativeConnectionCallback(ref NativeConnectionChange change, IntPtr userData);

    internal static class Native
    {
        // Mono maps this name to libhaptic_c.so.1 (Hapticd.dll.config); Unity loads the plug-in
        // libhaptic_c.so from the project's Plugins folder (docs/unity.md).
        internal const string Library = "haptic_c";
        internal const uint HeaderVersion = 1;
        internal const int Timeout = 100;

        [DllImport(Library)] internal static extern uint haptic_c_version();
        [DllImport(Library)] internal static extern void haptic_client_config_init(ref NativeClientConfigDefaults config);
        [DllImport(Library)] internal static extern int haptic_client_open(ref NativeClientConfig config, out IntPtr client, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_client_close(IntPtr client, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_client_device_info(IntPtr client, ref DeviceInfo info, IntPtr err);
        [DllImport(Library)] internal static extern ulong haptic_client_session_id(IntPtr client);
        [DllImport(Library)] internal static extern long haptic_client_lease_timeout_ms(IntPtr client);

        [DllImport(Library)] internal static extern int haptic_client_poll_state(IntPtr client, ref State state, uint timeoutMs, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_client_wait_for_tick(IntPtr client, ulong tick, ref State state, uint timeoutMs, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_client_subscribe(IntPtr client, uint decimation, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_client_on_state(IntPtr client, NativeStateCallback callback, IntPtr userData, IntPtr err);
        [DllImport(Library)] internal static extern long haptic_steady_clock_ns();
        [DllImport(Library)] internal static extern int haptic_client_server_time_at(IntPtr client, long localNs, out double serverTime);
        [DllImport(Library)] internal static extern int haptic_client_clock_offset_ns(IntPtr client, out long offsetNs);
        [DllImport(Library)] internal static extern int haptic_client_clock_drift(IntPtr client, out double drift);
        [DllImport(Library)] internal static extern Vec3 haptic_interpolate_position(ref State a, ref State b, double t);
        [DllImport(Library)] internal static extern Vec3 haptic_predict_position(ref State previous, ref State latest, double t);
        [DllImport(Library)] internal static extern int haptic_client_receive_counters(IntPtr client, ref ReceiveCounters counters, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_client_set_heartbeats_enabled(IntPtr client, int enabled, IntPtr err);

        [DllImport(Library)] internal static extern void haptic_wall_spec_init(ref WallSpec spec);
        [DllImport(Library)] internal static extern void haptic_sphere_spec_init(ref SphereSpec spec);
        [DllImport(Library)] internal static extern void haptic_box_spec_init(ref BoxSpec spec);
        [DllImport(Library)] internal static extern void haptic_capsule_spec_init(ref CapsuleSpec spec);
        [DllImport(Library)] internal static extern void haptic_tangent_plane_spec_init(ref TangentPlaneSpec spec);
        [DllImport(Library)] internal static extern void haptic_mesh_spec_init(ref NativeMeshSpec spec);
        [DllImport(Library)] internal static extern void haptic_spring_field_spec_init(ref SpringFieldSpec spec);
        [DllImport(Library)] internal static extern void haptic_distance_spring_spec_init(ref DistanceSpringSpec spec);
        [DllImport(Library)] internal static extern void haptic_potential_field_spec_init(ref PotentialFieldSpec spec);
        [DllImport(Library)] internal static extern void haptic_linear_field_spec_init(ref LinearFieldSpec spec);
        [DllImport(Library)] internal static extern void haptic_viscous_field_spec_init(ref ViscousFieldSpec spec);
        [DllImport(Library)] internal static extern void haptic_detent_field_spec_init(ref DetentFieldSpec spec);
        [DllImport(Library)] internal static extern void haptic_orientation_spring_spec_init(ref OrientationSpringSpec spec);
        [DllImport(Library)] internal static extern void haptic_orientation_detent_spec_init(ref OrientationDetentSpec spec);

        [DllImport(Library)] internal static extern int haptic_client_add_wall(IntPtr client, ref WallSpec spec, out IntPtr handle, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_client_add_sphere(IntPtr client, ref SphereSpec spec, out IntPtr handle, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_client_add_box(IntPtr client, ref BoxSpec spec, out IntPtr handle, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_client_add_capsule(IntPtr client, ref CapsuleSpec spec, out IntPtr handle, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_client_add_tangent_plane(IntPtr client, ref TangentPlaneSpec spec, out IntPtr handle, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_client_add_mesh(IntPtr client, ref NativeMeshSpec spec, out IntPtr handle, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_client_add_spring_field(IntPtr client, ref SpringFieldSpec spec, out IntPtr handle, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_client_add_distance_spring(IntPtr client, ref DistanceSpringSpec spec, out IntPtr handle, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_client_add_potential_field(IntPtr client, ref PotentialFieldSpec spec, out IntPtr handle, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_client_add_linear_field(IntPtr client, ref LinearFieldSpec spec, out IntPtr handle, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_client_add_viscous_field(IntPtr client, ref ViscousFieldSpec spec, out IntPtr handle, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_client_add_detent_field(IntPtr client, ref DetentFieldSpec spec, out IntPtr handle, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_client_add_orientation_spring(IntPtr client, ref OrientationSpringSpec spec, out IntPtr handle, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_client_add_orientation_detent(IntPtr client, ref OrientationDetentSpec spec, out IntPtr handle, IntPtr err);

        [DllImport(Library)] internal static extern int haptic_object_update_wall(IntPtr handle, ref WallSpec spec, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_object_update_sphere(IntPtr handle, ref SphereSpec spec, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_object_update_box(IntPtr handle, ref BoxSpec spec, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_object_update_capsule(IntPtr handle, ref CapsuleSpec spec, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_object_update_tangent_plane(IntPtr handle, ref TangentPlaneSpec spec, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_object_update_mesh(IntPtr handle, ref NativeMeshSpec spec, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_field_update_spring_field(IntPtr handle, ref SpringFieldSpec spec, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_field_update_distance_spring(IntPtr handle, ref DistanceSpringSpec spec, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_field_update_potential_field(IntPtr handle, ref PotentialFieldSpec spec, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_field_update_linear_field(IntPtr handle, ref LinearFieldSpec spec, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_field_update_viscous_field(IntPtr handle, ref ViscousFieldSpec spec, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_field_update_detent_field(IntPtr handle, ref DetentFieldSpec spec, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_field_update_orientation_spring(IntPtr handle, ref OrientationSpringSpec spec, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_field_update_orientation_detent(IntPtr handle, ref OrientationDetentSpec spec, IntPtr err);

        [DllImport(Library)] internal static extern ulong haptic_object_id(IntPtr handle);
        [DllImport(Library)] internal static extern ulong haptic_field_id(IntPtr handle);
        [DllImport(Library)] internal static extern int haptic_object_remove(IntPtr handle, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_field_remove(IntPtr handle, IntPtr err);
        [DllImport(Library)] internal static extern ulong haptic_object_release(IntPtr handle);
        [DllImport(Library)] internal static extern ulong haptic_field_release(IntPtr handle);
        [DllImport(Library)] internal static extern int haptic_object_stability(IntPtr handle, ref StabilityReport report, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_field_stability(IntPtr handle, ref StabilityReport report, IntPtr err);

        [DllImport(Library)] internal static extern int haptic_client_apply_scene(IntPtr client, [In] NativeSceneItem[] items, uint count, out IntPtr applied, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_client_apply_scene_file(IntPtr client, [MarshalAs(UnmanagedType.LPStr)] string path, out IntPtr applied, IntPtr err);
        [DllImport(Library)] internal static extern void haptic_applied_scene_counts(IntPtr applied, out uint objects, out uint fields);
        [DllImport(Library)] internal static extern IntPtr haptic_applied_scene_take_object(IntPtr applied, uint index);
        [DllImport(Library)] internal static extern IntPtr haptic_applied_scene_take_field(IntPtr applied, uint index);
        [DllImport(Library)] internal static extern int haptic_applied_scene_stability(IntPtr applied, uint index, ref StabilityReport report, IntPtr err);
        [DllImport(Library)] internal static extern void haptic_applied_scene_free(IntPtr applied);
        [DllImport(Library)] internal static extern int haptic_scene_json([In] NativeSceneItem[] items, uint count, byte[] buffer, UIntPtr capacity, out UIntPtr length, IntPtr err);

        [DllImport(Library)] internal static extern int haptic_client_scene(IntPtr client, int allSessions, out IntPtr scene, IntPtr err);
        [DllImport(Library)] internal static extern void haptic_registered_scene_counts(IntPtr scene, out uint objects, out uint fields);
        [DllImport(Library)] internal static extern int haptic_registered_scene_object(IntPtr scene, uint index, ref NativeSceneEntry entry, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_registered_scene_field(IntPtr scene, uint index, ref NativeSceneEntry entry, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_registered_scene_object_spec(IntPtr scene, uint index, IntPtr spec, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_registered_scene_field_spec(IntPtr scene, uint index, IntPtr spec, IntPtr err);
        [DllImport(Library)] internal static extern void haptic_registered_scene_free(IntPtr scene);

        [DllImport(Library)] internal static extern int haptic_client_scene_energy(IntPtr client, [Out] ItemEnergy[] items, uint capacity, out uint count, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_client_object_states(IntPtr client, [Out] ObjectState[] states, uint capacity, out uint count, IntPtr err);

        [DllImport(Library)] internal static extern int haptic_client_set_operator(IntPtr client, ref NativeOperatorInput input, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_client_step(IntPtr client, uint ticks, out ulong lastTick, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_client_reset(IntPtr client, IntPtr err);

        [DllImport(Library)] internal static extern int haptic_client_on_event(IntPtr client, NativeEventCallback callback, IntPtr userData, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_client_on_connection(IntPtr client, NativeConnectionCallback callback, IntPtr userData, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_client_connection_state(IntPtr client);

        [DllImport(Library)] internal static extern int haptic_client_sessions(IntPtr client, [Out] SessionSummary[] sessions, uint capacity, out uint count, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_client_kick_session(IntPtr client, ulong sessionId, [MarshalAs(UnmanagedType.LPStr)] string reason, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_client_stats(IntPtr client, ref StatsCounters stats, [Out] StreamStats[] clients, uint clientsCapacity, [Out] CouplingStats[] couplings, uint couplingsCapacity, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_client_start_recording(IntPtr client, [MarshalAs(UnmanagedType.LPStr)] string name, ref RecordingStatus status, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_client_stop_recording(IntPtr client, ref RecordingStatus status, IntPtr err);

        [DllImport(Library)] internal static extern int haptic_client_record(IntPtr client, ref NativeRecorderOptions options, out IntPtr recorder, IntPtr err);
        [DllImport(Library)] internal static extern int haptic_recorder_get_stats(IntPtr recorder, ref RecorderStats stats, IntPtr err);
        [DllImport(Library)] internal static extern IntPtr haptic_recorder_path(IntPtr recorder);
        [DllImport(Library)] internal static extern IntPtr haptic_recorder_events_path(IntPtr recorder);
        [DllImport(Library)] internal static extern int haptic_recorder_close(IntPtr recorder, ref RecorderStats totals, IntPtr err);
    }
}
