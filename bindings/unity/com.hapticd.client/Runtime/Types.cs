// Value types of the hapticd C# client: the C++ SDK's types (sdk/include/haptic/types.hpp) field
// for field, with its defaults. SI units; positions, velocities and forces in the device's world
// frame W (docs/architecture.md).
using System;

namespace Hapticd
{
    public struct Vec3
    {
        public double X, Y, Z;
        public Vec3(double x, double y, double z) { X = x; Y = y; Z = z; }
        public override string ToString() { return string.Format("({0}, {1}, {2})", X, Y, Z); }
    }

    /// <summary>Unit quaternion (w, x, y, z).</summary>
    public struct Quaternion
    {
        public double W, X, Y, Z;
        public Quaternion(double w, double x, double y, double z) { W = w; X = x; Y = y; Z = z; }
        public static Quaternion Identity { get { return new Quaternion(1, 0, 0, 0); } }
    }

    /// <summary>Where an object is: its origin (m) and orientation in W.</summary>
    public struct Pose
    {
        public Vec3 Position;
        public Quaternion Orientation;
        public Pose(Vec3 position, Quaternion orientation) { Position = position; Orientation = orientation; }
        public static Pose At(Vec3 position) { return new Pose(position, Quaternion.Identity); }
    }

    /// <summary>How penetration becomes force along a surface's normal (docs/scene.md).</summary>
    public enum ImpedanceLaw : int { Velocity = 0, BackwardDifference = 1, ExactZoh = 2, Tustin = 3 }

    /// <summary>A virtual spring-damper with optional Coulomb friction.</summary>
    public struct Impedance
    {
        public double Stiffness;       // N/m, finite, >= 0
        public double Damping;         // N·s/m, finite, >= 0
        public double StaticFriction;
        public double DynamicFriction;
        public double Mass;            // kg, of the discrete laws
        public ImpedanceLaw Law;
        public bool TransparencyOptimalDamping;
        public bool VirtualCoupling;
        public Impedance(double stiffness, double damping) : this() { Stiffness = stiffness; Damping = damping; }
    }

    /// <summary>Mass > 0 makes an object a body the tool can push (000 eq. 7.1).</summary>
    public struct Dynamics
    {
        public double Mass;     // kg; 0: fixed
        public double Damping;  // N·s/m
        public Dynamics(double mass, double damping) { Mass = mass; Damping = damping; }
    }

    public enum DistanceKind : int { Point = 0, Line = 1, Plane = 2, Sphere = 3 }

    /// <summary>The distance function the fields are built on.</summary>
    public struct Distance
    {
        public DistanceKind Kind;
        public Vec3 Origin;   // m
        public Vec3 Axis;     // Line: direction; Plane: normal
        public double Radius; // Sphere, m
        /// <summary>A point distance about the origin, axis +z (the C++ SDK's default).</summary>
        public static Distance Default { get { return new Distance { Axis = new Vec3(0, 0, 1) }; } }
    }

    // ---- object specs: each has Default (the C++ SDK's defaults, from the library) ----

    /// <summary>A plane the tool stays above: through Point, outward Normal.</summary>
    public struct WallSpec
    {
        public Vec3 Point;
        public Vec3 Normal;
        public Impedance Impedance;
        public bool Shared;
        public bool AcrossSites;
        public static WallSpec Default { get { return new WallSpec { Normal = new Vec3(0, 0, 1) }; } }
    }
    public struct SphereSpec
    {
        public Vec3 Center;
        public double Radius;
        public Impedance Impedance;
        public Dynamics Dynamics;
        public bool Shared;
        public bool AcrossSites;
        public static SphereSpec Default { get { return new SphereSpec(); } }
    }
    public struct BoxSpec
    {
        public Pose Pose;
        public Vec3 HalfExtents;
        public Impedance Impedance;
        public Dynamics Dynamics;
        public bool Shared;
        public bool AcrossSites;
        public static BoxSpec Default { get { return new BoxSpec { Pose = Pose.At(new Vec3()) }; } }
    }
    public struct CapsuleSpec
    {
        public Pose Pose;
        public double Radius;
        public double HalfLength;
        public Impedance Impedance;
        public Dynamics Dynamics;
        public bool Shared;
        public bool AcrossSites;
        public static CapsuleSpec Default { get { return new CapsuleSpec { Pose = Pose.At(new Vec3()) }; } }
    }

    /// <summary>Russo's tangent-plane local model.</summary>
    public struct TangentPlaneSpec
    {
        public Pose Pose;
        public Vec3 Normal;
        public Vec3 Reference;
        public double TangentialStiffness;
        public double TangentialDamping;
        public Impedance Impedance;
        public bool AcrossSites;
        public static TangentPlaneSpec Default { get { return new TangentPlaneSpec { Pose = Pose.At(new Vec3()), Normal = new Vec3(0, 0, 1) }; } }
    }

    /// <summary>A triangle mesh in its pose's frame: three indices per triangle.</summary>
    public sealed class MeshSpec
    {
        public Pose Pose = Pose.At(new Vec3());
        public Vec3[] Vertices = new Vec3[0];
        public uint[] Indices = new uint[0];
        public Impedance Impedance;
        public bool Shared;
        public bool AcrossSites;
    }

    // ---- field specs ----
    public struct SpringFieldSpec
    {
        public Vec3 Anchor;
        public double Stiffness;
        public double Damping;
        public double MaxForce;
        public bool AcrossSites;
        public static SpringFieldSpec Default { get { return new SpringFieldSpec(); } }
    }
    public struct DistanceSpringSpec
    {
        public Distance Anchor;
        public double Stiffness;
        public double Damping;
        public double MaxForce;
        public bool AcrossSites;
        public static DistanceSpringSpec Default { get { return new DistanceSpringSpec { Anchor = Distance.Default }; } }
    }

    public enum PotentialKind : int { Polynomial = 0, Khatib = 1 }
    public struct PotentialFieldSpec
    {
        public Distance Distance;
        public PotentialKind Kind;
        public uint Order;
        public double Gain;
        public double Offset;
        public double InfluenceDistance;
        public double MinDistance;
        public bool CentralDifferences;
        public bool AcrossSites;
        public static PotentialFieldSpec Default { get { return new PotentialFieldSpec { Distance = Distance.Default, Order = 2 }; } }
    }

    /// <summary>F = F0 + K (p − origin) inside Radius; K's rows are JacobianRow0..2 (N/m).</summary>
    public struct LinearFieldSpec
    {
        public Vec3 Origin;
        public Vec3 Force;
        public Vec3 JacobianRow0;
        public Vec3 JacobianRow1;
        public Vec3 JacobianRow2;
        public double Radius;
        public double FadeWidth;
        public bool AcrossSites;
        public static LinearFieldSpec Default { get { return new LinearFieldSpec(); } }
    }
    public struct ViscousFieldSpec
    {
        public double Damping;
        public Vec3 Center;
        public double Radius;
        public double FadeWidth;
        public bool AcrossSites;
        public static ViscousFieldSpec Default { get { return new ViscousFieldSpec(); } }
    }
    public struct DetentFieldSpec
    {
        public Distance Distance;
        public double Depth;
        public double Radius;
        public double RimHeight;
        public double RimWidth;
        public bool AcrossSites;
        public static DetentFieldSpec Default { get { return new DetentFieldSpec { Distance = Distance.Default }; } }
    }
    public struct OrientationSpringSpec
    {
        public Quaternion Target;
        public double Stiffness;
        public double Damping;
        public double MaxTorque;
        public ImpedanceLaw Law;
        public bool AcrossSites;
        public static OrientationSpringSpec Default { get { return new OrientationSpringSpec { Target = Quaternion.Identity }; } }
    }
    public struct OrientationDetentSpec
    {
        public Quaternion Target;
        public double Depth;
        public double Radius;
        public double RimHeight;
        public double RimWidth;
        public double Damping;
        public bool AcrossSites;
        public static OrientationDetentSpec Default { get { return new OrientationDetentSpec { Target = Quaternion.Identity }; } }
    }

    // ---- state and reports ----

    [Flags]
    public enum StateFlags : uint { None = 0, ForceSaturated = 1, ForceFault = 2, RampingOut = 4, DeviceFault = 8 }

    /// <summary>A sample of the tool. Local times are steady-clock nanoseconds (Client.SteadyClockNs).</summary>
    public struct State
    {
        public ulong Tick;
        public ulong Sequence;         // 0 from a Step reply
        public double ServerTime;      // s
        public Vec3 Position;          // p_WT, m
        public Vec3 Velocity;          // v_WT, m/s
        public Vec3 Force;             // F_T_W commanded, N
        public Vec3 Proxy;             // contact point, m
        public uint ContactCount;
        public StateFlags Flags;
        public uint Buttons;           // bit i: button i
        public Quaternion Orientation; // R_WT when HasOrientation
        public Vec3 Torque;            // tau_T_W commanded, N·m
        public long ReceivedAtNs;
        public long ArrivedAtNs;       // the kernel's receive stamp; 0: none
        public long AgeNs;             // how much longer than the quickest recent sample it took
        /// <summary>A StateOriented sample: Orientation and Torque are the device's.</summary>
        public bool HasOrientation { get; internal set; }
    }

    [Flags]
    public enum Capabilities : uint
    {
        None = 0, Gravity = 1 << 0, Brakes = 1 << 1, FlexibleModes = 1 << 2, Friction = 1 << 3,
        ForceSensor = 1 << 4, QuantizedPosition = 1 << 5, StateEstimator = 1 << 6,
        DisturbanceObserver = 1 << 7, Orientation = 1 << 8, Torque = 1 << 9
    }

    /// <summary>The device, as reported when the session opened.</summary>
    public struct DeviceInfo
    {
        public string Name;
        public string Model;
        public Capabilities Capabilities;
        public uint Dof;
        public Vec3 WorkspaceMin;
        public Vec3 WorkspaceMax;
        public double MaxForce;
        public double LoopRateHz;
        public double MaxTorque;
        public bool Simulated;
        public uint Buttons;
    }

    /// <summary>The server's stability report for an impedance (docs/scene.md).</summary>
    public struct StabilityReport
    {
        public bool Available;
        public double ColgateMinDamping;
        public double DeviceMass;
        public double DeviceDamping;
        public double MaxStableStiffness;
        public double MaxPoleMagnitude;
        public double ChosenDamping;
        public double ChosenStiffness;
        public bool Passive;
        public bool DeviceKnown;
        public bool Stable;
        public bool RobustlyStable;
        public string Warning;
    }
    public struct ReceiveCounters
    {
        public ulong Accepted, Rejected, Skipped, ChallengesAnswered, CallbackSkipped, Lost, Reordered,
            Duplicates, Reconnects;
    }
    public struct ItemEnergy
    {
        public ulong Id;
        public ulong SessionId;
        public bool IsObject;
        public double GivenToDevice;       // J
        public double AbsorbedFromDevice;  // J
    }
    public struct ObjectState
    {
        public ulong Id;
        public Vec3 Position;
        public Vec3 Velocity;
    }

    public enum Role : int { None = 0, Observer = 1, Controller = 2, Admin = 3 }
    public struct SessionSummary
    {
        public ulong SessionId;
        public string ClientName;
        public string Peer;
        public string TokenName;
        public uint DeviceIndex;
        public Role Role;
        public double OpenedTime;
    }

    /// <summary>One client's state stream in Stats.</summary>
    public struct StreamStats
    {
        public ulong SessionId;
        public string ClientName;
        public string Peer;
        public uint DeviceIndex;
        public uint Decimation;
        public ulong DatagramsSent, Heartbeats, StatesReceived, StatesLost;
        public double LastHeartbeatAgeS;
        public uint RoundTripSamples;
        public double RoundTripP50Us, RoundTripP99Us, RoundTripP999Us;
    }

    /// <summary>One coupling of a federation (docs/federation.md). Unit: J.</summary>
    public struct CouplingStats
    {
        public int Kind;  // 0: tool, 1: shared mass
        public uint Port;
        public ulong Remote, Mass;
        public double InjectedJ, GivenJ, SentJ, ReceivedJ, ReservoirJ;
    }

    /// <summary>The server's counters (GetStats), as haptic_stats lays them out.</summary>
    public struct StatsCounters
    {
        public uint Sessions;
        public ulong Ticks;
        public double AchievedRateHz, LatenessP50Us, LatenessP99Us, LatenessP999Us, LatenessMaxUs;
        public ulong LatenessSamples;
        public double WindowS;
        public ulong Overruns;
        public uint Objects, Fields;
        public ulong DatagramsSent, DatagramsReceived, DatagramsDropped, ForceFaults, ForceSaturations,
            PassivityActiveTicks, LeasesExpired, DeviceFaults;
        public double SendDelayP50Us, SendDelayP99Us, SendDelayP999Us;
        public ulong HeartbeatsRateLimited, DatagramsForeignSource, PathChallengesSent, SamplesSkipped,
            ConnectionsRefused, ConnectionsTimedOut, ConnectionsEvicted, TlsHandshakesFailed;
        public uint ConnectionsOpen;
        public uint ClientCount;
        public bool HasFederation;
        public uint CouplingCount;
        public ulong FederationSamplesPublished, FederationSamplesFailed, FederationItemsPublished,
            FederationItemsApplied, FederationItemsRefused, FederationWrenchesAccepted,
            FederationWrenchesRefused;
    }

    public sealed class Stats
    {
        public StatsCounters Counters;
        public StreamStats[] Clients = new StreamStats[0];
        public CouplingStats[] Couplings = new CouplingStats[0];
    }
    public struct RecordingStatus
    {
        public string Path;
        public ulong StartTick, Samples, SamplesMissed, Changes, RecordsNotWritten;
        public string WriteError;
    }

    public enum EventKind : int
    {
        Unknown = 0, SessionOpened = 1, SessionClosed = 2, LeaseExpired = 3, SceneChanged = 4,
        ForceFault = 5, WatchStarted = 6, DeviceFault = 7, Reset = 8
    }

    /// <summary>Something that happened on the server.</summary>
    public sealed class Event
    {
        public EventKind Kind;
        public ulong SessionId;
        public ulong ItemId;
        public double ServerTime;
        public string Message = "";
    }

    public enum ConnectionState : int { Connected = 0, Lost = 1, Resumed = 2, Ended = 3 }

    public sealed class ConnectionChange
    {
        public ConnectionState State;
        public ulong SessionId;
        public bool NewSession;
        public uint ItemsNotRestored;
        public long OutageMs;
        public string Reason = "";
    }

    public enum OperatorMode : int { Release = 0, Follow = 1, Push = 2 }
    public enum Grip : int { Custom = 0, Loose = 1, Tight = 2 }
    public enum PathShape : int { Fixed = 0, Line = 1, Sine = 2 }
    public enum ProfileShape : int { Constant = 0, Step = 1, Ramp = 2, Sine = 3, Recorded = 4 }

    /// <summary>What the server's simulated hand does (haptic::OperatorInput).</summary>
    public sealed class OperatorInput
    {
        public OperatorMode Mode;
        public Vec3 Target;
        public double Stiffness, Damping, Mass;
        public Grip Grip;
        public PathShape PathShape;
        public Vec3 PathEnd;
        public double PathDurationS;
        public Vec3 PathAmplitude;
        public double PathFrequencyHz;
        public Vec3 Force;
        public ProfileShape ProfileShape;
        public bool ProfileRepeat;
        public double ProfileStartS, ProfileRiseS, ProfileFrequencyHz;
        public Vec3 ProfileOffset;
        public Vec3[] ProfileSamples = new Vec3[0];
        public double ProfileSamplePeriodS;

        public static OperatorInput Release() { return new OperatorInput(); }
        public static OperatorInput Push(Vec3 force) { return new OperatorInput { Mode = OperatorMode.Push, Force = force }; }
        public static OperatorInput Follow(Vec3 target, double stiffness, double damping)
        {
            return new OperatorInput { Mode = OperatorMode.Follow, Target = target, Stiffness = stiffness, Damping = damping };
        }
    }

    public enum RecorderFormat : int { Auto = 0, Csv = 1, Hdf5 = 2 }

    /// <summary>What Client.Record writes and where (haptic::RecorderOptions; docs/recorder.md).</summary>
    public sealed class RecorderOptions
    {
        public string Path = "";          // .csv, or .h5 / .hdf5 with Auto
        public RecorderFormat Format = RecorderFormat.Auto;
        public ulong QueueCapacity = 65536;  // samples between the receive thread and the writer
        public bool Events = true;        // the server's events and the connection's changes
        public bool Overwrite = false;    // an existing file is refused unless set
    }

    /// <summary>A recorder's totals (haptic::RecorderStats).</summary>
    public struct RecorderStats
    {
        public ulong SamplesReceived, SamplesWritten, Dropped, EventsWritten, EventsDropped, WriteErrors;
        public string FirstError;
    }

    /// <summary>The SDK's error kinds (haptic_status).</summary>
    public enum ErrorCode : int
    {
        Ok = 0, Connection = 1, InvalidArgument = 2, NotFound = 3, PermissionDenied = 4,
        ResourceExhausted = 5, FailedPrecondition = 6, VersionMismatch = 7, Internal = 8,
        Unauthenticated = 9
    }

    /// <summary>A refused or failed call: the code and the SDK's "call: field: problem" message.</summary>
    public class HapticException : Exception
    {
        public ErrorCode Code { get; private set; }
        public HapticException(ErrorCode code, string message) : base(message) { Code = code; }
    }
}
